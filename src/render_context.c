/* render_context.c -- the off-screen GL context behind the renderer.
 *
 * A context is a backend (a small table of functions) plus its private
 * state.  OSMesa is the only backend built today: it renders with Mesa's
 * llvmpipe into a buffer we own, with the GL compatibility profile, so the
 * fixed-function pipeline works.  Mesa 25.1 removed OSMesa; an EGL
 * surfaceless backend (EGL_MESA_platform_surfaceless, a pbuffer-less context
 * drawing into a framebuffer object, glReadPixels to read) would be a second
 * entry in ss_gl_backends[] with the same four operations; nothing outside
 * this file would change. */
#include "render.h"

#include <GL/osmesa.h>
#include <stdlib.h>
#include <string.h>

typedef struct ssGLBackend {
  const char *name;
  /* fill ctx->impl; SS_OK or an error */
  ssStatus (*create)(ssGLContext *ctx, ssError *err);
  ssStatus (*make_current)(ssGLContext *ctx, ssError *err);
  /* glFinish, then copy the colour buffer, top row first */
  ssStatus (*read_rgba)(ssGLContext *ctx, unsigned char *rgba, ssError *err);
  void (*destroy)(ssGLContext *ctx);
} ssGLBackend;

struct ssGLContext {
  const ssGLBackend *backend;
  int width, height;
  void *impl; /* backend state */
};

/* ---------------------------------------------------------------------- */
/* OSMesa backend                                                          */

typedef struct osmesaImpl {
  OSMesaContext ctx;
  unsigned char *buffer; /* width*height*4, bottom row first (GL order) */
} osmesaImpl;

static ssStatus osmesa_create(ssGLContext *c, ssError *err)
{
  osmesaImpl *o = calloc(1, sizeof *o);
  if (!o) return ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
  c->impl = o;
  o->buffer = malloc((size_t)c->width * (size_t)c->height * 4);
  if (!o->buffer)
    return ss_error_set(err, SS_ERR_NOMEM, "", 0,
                        "out of memory for a %d x %d frame buffer", c->width,
                        c->height);
  /* RGBA, 24-bit depth, no stencil or accumulation, compatibility profile */
  o->ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  if (!o->ctx)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "cannot create an OSMesa context (RGBA, 24-bit depth)");
  if (!OSMesaMakeCurrent(o->ctx, o->buffer, GL_UNSIGNED_BYTE, c->width,
                         c->height))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "OSMesa cannot render a %d x %d image", c->width,
                        c->height);
  GLint maxdims[2] = {0, 0};
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, maxdims);
  if (maxdims[0] > 0 && (c->width > maxdims[0] || c->height > maxdims[1]))
    return ss_error_set(err, SS_ERR_VALUE, "", 0,
                        "image size %d x %d exceeds the GL limit %d x %d",
                        c->width, c->height, (int)maxdims[0], (int)maxdims[1]);
  return SS_OK;
}

static ssStatus osmesa_make_current(ssGLContext *c, ssError *err)
{
  osmesaImpl *o = c->impl;
  if (!OSMesaMakeCurrent(o->ctx, o->buffer, GL_UNSIGNED_BYTE, c->width,
                         c->height))
    return ss_error_set(err, SS_ERR_STATE, "", 0,
                        "cannot make the OSMesa context current");
  return SS_OK;
}

static ssStatus osmesa_read_rgba(ssGLContext *c, unsigned char *rgba,
                                 ssError *err)
{
  osmesaImpl *o = c->impl;
  (void)err;
  glFinish();
  /* OSMesa draws straight into our buffer, bottom row first */
  size_t row = (size_t)c->width * 4;
  for (int y = 0; y < c->height; y++)
    memcpy(rgba + row * (size_t)y, o->buffer + row * (size_t)(c->height - 1 - y),
           row);
  return SS_OK;
}

static void osmesa_destroy(ssGLContext *c)
{
  osmesaImpl *o = c->impl;
  if (!o) return;
  /* unbind first: a context destroyed while current keeps its frame buffer */
  if (o->ctx && OSMesaGetCurrentContext() == o->ctx)
    OSMesaMakeCurrent(NULL, NULL, 0, 0, 0);
  if (o->ctx) OSMesaDestroyContext(o->ctx);
  free(o->buffer);
  free(o);
  c->impl = NULL;
}

static const ssGLBackend ss_gl_osmesa = {
  "OSMesa", osmesa_create, osmesa_make_current, osmesa_read_rgba,
  osmesa_destroy};

/* Backends in order of preference (an EGL surfaceless one would go here). */
static const ssGLBackend *const ss_gl_backends[] = {&ss_gl_osmesa};

/* ---------------------------------------------------------------------- */
/* interface                                                               */

ssGLContext *ss_glctx_new(int width, int height, ssError *err)
{
  if (width < 1 || height < 1 || width > SS_RENDER_MAX_SIDE ||
      height > SS_RENDER_MAX_SIDE) {
    ss_error_set(err, SS_ERR_VALUE, "", 0,
                 "invalid image size %d x %d (each side must be 1 to %d "
                 "pixels)",
                 width, height, SS_RENDER_MAX_SIDE);
    return NULL;
  }
  ssError first;
  memset(&first, 0, sizeof first);
  size_t nb = sizeof ss_gl_backends / sizeof ss_gl_backends[0];
  for (size_t k = 0; k < nb; k++) {
    ssGLContext *c = calloc(1, sizeof *c);
    if (!c) {
      ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
      return NULL;
    }
    c->backend = ss_gl_backends[k];
    c->width = width;
    c->height = height;
    ssError e;
    memset(&e, 0, sizeof e);
    if (c->backend->create(c, &e) == SS_OK) return c;
    /* keep the first backend's reason: it is the preferred one */
    if (k == 0) first = e;
    c->backend->destroy(c);
    free(c);
  }
  if (err) *err = first;
  return NULL;
}

ssStatus ss_glctx_make_current(ssGLContext *c, ssError *err)
{
  return c->backend->make_current(c, err);
}

ssStatus ss_glctx_read_rgba(ssGLContext *c, unsigned char *rgba, ssError *err)
{
  return c->backend->read_rgba(c, rgba, err);
}

const char *ss_glctx_backend_name(const ssGLContext *c)
{
  return c ? c->backend->name : "none";
}

void ss_glctx_free(ssGLContext *c)
{
  if (!c) return;
  c->backend->destroy(c);
  free(c);
}
