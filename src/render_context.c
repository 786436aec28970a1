/* render_context.c -- the off-screen GL context behind the renderer.
 *
 * A context is a backend (a small table of functions) plus its private
 * state.  Two backends, both Mesa's llvmpipe with the GL compatibility
 * profile (the renderer uses the fixed-function pipeline):
 *  - OSMesa renders into a buffer we own.  Debian 12's Mesa ships it; Mesa
 *    25.1 removed it.
 *  - EGL surfaceless (EGL_MESA_platform_surfaceless through
 *    eglGetPlatformDisplayEXT): a context without any surface, drawing into
 *    a framebuffer object of its own, read back with glReadPixels.  Built
 *    when configure finds libegl-dev (SS_HAVE_EGL).
 * Which one: SOILSIM_GL=osmesa|egl in the environment, else the configure
 * default (--with-gl, SS_GL_DEFAULT), else the first that starts.  A backend
 * named in SOILSIM_GL is the only one tried, so a request for EGL never
 * silently renders with OSMesa.
 *
 * GL calls go through libOSMesa's entry points (it is linked first), which
 * dispatch through Mesa's shared glapi to whatever context is current, so
 * one binary drives both backends.  When two contexts of different backends
 * live in one process, each make-current fully rebinds (see gl_current). */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif
#include "render.h"

#include <GL/osmesa.h>
#include <stdlib.h>
#include <string.h>

#ifdef SS_HAVE_EGL
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glext.h>
#endif

#ifndef SS_GL_DEFAULT
#define SS_GL_DEFAULT "osmesa"
#endif

typedef struct ssGLBackend {
  const char *key;  /* SOILSIM_GL value */
  const char *name; /* for messages and ss_glctx_backend_name */
  /* fill ctx->impl, leave the context current; SS_OK or an error */
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

/* The context this file last made current (any backend).  A backend whose
 * own API still believes its context is current (EGL through libglvnd) must
 * rebind anyway when another backend's context was made current since. */
static const ssGLContext *gl_current;

/* Refuse sizes beyond the implementation's limits (the context is current). */
static ssStatus check_gl_limits(const ssGLContext *c, ssError *err)
{
  GLint maxdims[2] = {0, 0};
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, maxdims);
  if (maxdims[0] > 0 && (c->width > maxdims[0] || c->height > maxdims[1]))
    return ss_error_set(err, SS_ERR_VALUE, "", 0,
                        "image size %d x %d exceeds the GL limit %d x %d",
                        c->width, c->height, (int)maxdims[0], (int)maxdims[1]);
  return SS_OK;
}

/* Copy a bottom-row-first frame into rgba, top row first. */
static void flip_rows(const ssGLContext *c, const unsigned char *src,
                      unsigned char *rgba)
{
  size_t row = (size_t)c->width * 4;
  for (int y = 0; y < c->height; y++)
    memcpy(rgba + row * (size_t)y, src + row * (size_t)(c->height - 1 - y), row);
}

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
  gl_current = c;
  return check_gl_limits(c, err);
}

static ssStatus osmesa_make_current(ssGLContext *c, ssError *err)
{
  osmesaImpl *o = c->impl;
  if (!OSMesaMakeCurrent(o->ctx, o->buffer, GL_UNSIGNED_BYTE, c->width,
                         c->height))
    return ss_error_set(err, SS_ERR_STATE, "", 0,
                        "cannot make the OSMesa context current");
  gl_current = c;
  return SS_OK;
}

static ssStatus osmesa_read_rgba(ssGLContext *c, unsigned char *rgba,
                                 ssError *err)
{
  osmesaImpl *o = c->impl;
  (void)err;
  glFinish();
  /* OSMesa draws straight into our buffer, bottom row first */
  flip_rows(c, o->buffer, rgba);
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
  "osmesa", "OSMesa", osmesa_create, osmesa_make_current, osmesa_read_rgba,
  osmesa_destroy};

/* ---------------------------------------------------------------------- */
/* EGL surfaceless backend                                                 */

#ifdef SS_HAVE_EGL

/* The surfaceless display is one per process: eglGetPlatformDisplayEXT
 * returns the same handle every time and eglTerminate would end every
 * context on it, so it is initialized by the first EGL context and
 * terminated with the last.  (Like GL itself, contexts are made and freed
 * from one thread.) */
static EGLDisplay egl_display = EGL_NO_DISPLAY;
static int egl_users;

typedef struct eglImpl {
  EGLContext ctx;
  int counted;           /* holds a reference on egl_display */
  GLuint fbo, rb_color, rb_depth;
  unsigned char *buffer; /* width*height*4 read back, bottom row first */
  PFNGLBINDFRAMEBUFFERPROC bind_fbo;
  PFNGLDELETEFRAMEBUFFERSPROC delete_fbos;
  PFNGLDELETERENDERBUFFERSPROC delete_rbs;
} eglImpl;

static const char *egl_error_name(EGLint e)
{
  switch (e) {
  case EGL_SUCCESS: return "EGL_SUCCESS";
  case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
  case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
  case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
  case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
  case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
  case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
  case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
  case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
  case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
  default: return "an EGL error";
  }
}

/* Does the space-separated extension list contain name exactly? */
static int has_extension(const char *list, const char *name)
{
  size_t n = strlen(name);
  for (const char *p = list; p && *p;) {
    const char *e = strchr(p, ' ');
    size_t len = e ? (size_t)(e - p) : strlen(p);
    if (len == n && memcmp(p, name, n) == 0) return 1;
    if (!e) break;
    p = e + 1;
  }
  return 0;
}

static ssStatus egl_display_acquire(ssError *err)
{
  if (egl_users > 0) {
    egl_users++;
    return SS_OK;
  }
  const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!has_extension(client, "EGL_MESA_platform_surfaceless") ||
      !has_extension(client, "EGL_EXT_platform_base"))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: the surfaceless platform "
                        "(EGL_MESA_platform_surfaceless) is not available");
  PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
      (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
  if (!get_display)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: eglGetPlatformDisplayEXT is missing");
  EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
  EGLint major = 0, minor = 0;
  if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: cannot initialize the surfaceless display (%s)",
                        egl_error_name(eglGetError()));
  egl_display = dpy;
  egl_users = 1;
  return SS_OK;
}

static void egl_display_release(void)
{
  if (egl_users <= 0) return;
  if (--egl_users == 0) {
    eglTerminate(egl_display);
    eglReleaseThread();
    egl_display = EGL_NO_DISPLAY;
  }
}

static ssStatus egl_bind(ssGLContext *c, ssError *err)
{
  eglImpl *e = c->impl;
  /* libglvnd skips a make-current of the context it thinks is current, so
   * after another backend's context was current, unbind first */
  if (gl_current != c && eglGetCurrentContext() == e->ctx)
    eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (eglGetCurrentContext() != e->ctx &&
      !eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, e->ctx))
    return ss_error_set(err, SS_ERR_STATE, "", 0,
                        "EGL: cannot make the context current (%s)",
                        egl_error_name(eglGetError()));
  gl_current = c;
  if (e->fbo) e->bind_fbo(GL_FRAMEBUFFER, e->fbo);
  return SS_OK;
}

static ssStatus egl_create(ssGLContext *c, ssError *err)
{
  eglImpl *e = calloc(1, sizeof *e);
  if (!e) return ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
  c->impl = e;
  e->buffer = malloc((size_t)c->width * (size_t)c->height * 4);
  if (!e->buffer)
    return ss_error_set(err, SS_ERR_NOMEM, "", 0,
                        "out of memory for a %d x %d frame buffer", c->width,
                        c->height);
  ssStatus st = egl_display_acquire(err);
  if (st != SS_OK) return st;
  e->counted = 1;
  const char *dext = eglQueryString(egl_display, EGL_EXTENSIONS);
  if (!has_extension(dext, "EGL_KHR_surfaceless_context"))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: the display cannot make a context current "
                        "without a surface (EGL_KHR_surfaceless_context)");
  if (!eglBindAPI(EGL_OPENGL_API))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: desktop OpenGL is not available (%s)",
                        egl_error_name(eglGetError()));
  /* any OpenGL config: the context never gets a surface */
  EGLint cattr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig cfg = NULL;
  EGLint ncfg = 0;
  if (!eglChooseConfig(egl_display, cattr, &cfg, 1, &ncfg)) ncfg = 0;
  if (ncfg < 1 && !has_extension(dext, "EGL_KHR_no_config_context") &&
      !has_extension(dext, "EGL_MESA_configless_context"))
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: no OpenGL configuration on the surfaceless display");
  /* the compatibility profile: the renderer uses fixed-function GL */
  EGLint xattr[] = {EGL_CONTEXT_OPENGL_PROFILE_MASK,
                    EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT, EGL_NONE};
  e->ctx = eglCreateContext(egl_display, ncfg > 0 ? cfg : (EGLConfig)0,
                            EGL_NO_CONTEXT, xattr);
  if (e->ctx == EGL_NO_CONTEXT)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: cannot create an OpenGL compatibility context (%s)",
                        egl_error_name(eglGetError()));
  gl_current = NULL;
  if ((st = egl_bind(c, err)) != SS_OK) return st;

  /* a framebuffer object: RGBA8 colour and 24-bit depth renderbuffers */
  PFNGLGENFRAMEBUFFERSPROC gen_fbos =
      (PFNGLGENFRAMEBUFFERSPROC)eglGetProcAddress("glGenFramebuffers");
  PFNGLGENRENDERBUFFERSPROC gen_rbs =
      (PFNGLGENRENDERBUFFERSPROC)eglGetProcAddress("glGenRenderbuffers");
  PFNGLBINDRENDERBUFFERPROC bind_rb =
      (PFNGLBINDRENDERBUFFERPROC)eglGetProcAddress("glBindRenderbuffer");
  PFNGLRENDERBUFFERSTORAGEPROC rb_storage =
      (PFNGLRENDERBUFFERSTORAGEPROC)eglGetProcAddress("glRenderbufferStorage");
  PFNGLFRAMEBUFFERRENDERBUFFERPROC attach =
      (PFNGLFRAMEBUFFERRENDERBUFFERPROC)eglGetProcAddress("glFramebufferRenderbuffer");
  PFNGLCHECKFRAMEBUFFERSTATUSPROC fb_status =
      (PFNGLCHECKFRAMEBUFFERSTATUSPROC)eglGetProcAddress("glCheckFramebufferStatus");
  e->bind_fbo = (PFNGLBINDFRAMEBUFFERPROC)eglGetProcAddress("glBindFramebuffer");
  e->delete_fbos = (PFNGLDELETEFRAMEBUFFERSPROC)eglGetProcAddress("glDeleteFramebuffers");
  e->delete_rbs = (PFNGLDELETERENDERBUFFERSPROC)eglGetProcAddress("glDeleteRenderbuffers");
  if (!gen_fbos || !gen_rbs || !bind_rb || !rb_storage || !attach || !fb_status ||
      !e->bind_fbo || !e->delete_fbos || !e->delete_rbs)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: the context has no framebuffer objects");
  if ((st = check_gl_limits(c, err)) != SS_OK) return st;
  gen_fbos(1, &e->fbo);
  e->bind_fbo(GL_FRAMEBUFFER, e->fbo);
  gen_rbs(1, &e->rb_color);
  bind_rb(GL_RENDERBUFFER, e->rb_color);
  rb_storage(GL_RENDERBUFFER, GL_RGBA8, c->width, c->height);
  attach(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, e->rb_color);
  gen_rbs(1, &e->rb_depth);
  bind_rb(GL_RENDERBUFFER, e->rb_depth);
  rb_storage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, c->width, c->height);
  attach(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e->rb_depth);
  bind_rb(GL_RENDERBUFFER, 0);
  GLenum fs = fb_status(GL_FRAMEBUFFER);
  if (fs != GL_FRAMEBUFFER_COMPLETE)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: a %d x %d framebuffer object is incomplete "
                        "(status 0x%x)",
                        c->width, c->height, (unsigned)fs);
  glDrawBuffer(GL_COLOR_ATTACHMENT0);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  GLenum ge = glGetError();
  if (ge != GL_NO_ERROR)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                        "EGL: GL error 0x%x setting up the framebuffer",
                        (unsigned)ge);
  return SS_OK;
}

static ssStatus egl_make_current(ssGLContext *c, ssError *err)
{
  return egl_bind(c, err);
}

static ssStatus egl_read_rgba(ssGLContext *c, unsigned char *rgba, ssError *err)
{
  eglImpl *e = c->impl;
  glFinish();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glReadPixels(0, 0, c->width, c->height, GL_RGBA, GL_UNSIGNED_BYTE, e->buffer);
  GLenum ge = glGetError();
  if (ge != GL_NO_ERROR)
    return ss_error_set(err, SS_ERR_STATE, "", 0,
                        "EGL: GL error 0x%x reading the frame back", (unsigned)ge);
  flip_rows(c, e->buffer, rgba);
  return SS_OK;
}

static void egl_destroy(ssGLContext *c)
{
  eglImpl *e = c->impl;
  if (!e) return;
  if (e->ctx != EGL_NO_CONTEXT && e->ctx) {
    /* the framebuffer's objects go with the context; delete them while it
     * is current so that nothing outlives it in a shared namespace */
    if (e->fbo && egl_bind(c, NULL) == SS_OK) {
      e->bind_fbo(GL_FRAMEBUFFER, 0);
      e->delete_fbos(1, &e->fbo);
      if (e->rb_color) e->delete_rbs(1, &e->rb_color);
      if (e->rb_depth) e->delete_rbs(1, &e->rb_depth);
    }
    if (eglGetCurrentContext() == e->ctx)
      eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(egl_display, e->ctx);
  }
  if (gl_current == c) gl_current = NULL;
  if (e->counted) egl_display_release();
  free(e->buffer);
  free(e);
  c->impl = NULL;
}

static const ssGLBackend ss_gl_egl = {
  "egl", "EGL", egl_create, egl_make_current, egl_read_rgba, egl_destroy};

#endif /* SS_HAVE_EGL */

/* Backends built into this program. */
static const ssGLBackend *const ss_gl_backends[] = {
  &ss_gl_osmesa,
#ifdef SS_HAVE_EGL
  &ss_gl_egl,
#endif
};
#define SS_GL_NBACKEND (sizeof ss_gl_backends / sizeof ss_gl_backends[0])

static const ssGLBackend *backend_by_key(const char *key)
{
  for (size_t k = 0; k < SS_GL_NBACKEND; k++)
    if (strcmp(ss_gl_backends[k]->key, key) == 0) return ss_gl_backends[k];
  return NULL;
}

/* ---------------------------------------------------------------------- */
/* interface                                                               */

int ss_glctx_backend_built(const char *key)
{
  return key && backend_by_key(key) != NULL;
}

const char *ss_glctx_default_backend(void)
{
  return SS_GL_DEFAULT;
}

static ssGLContext *try_backend(const ssGLBackend *b, int width, int height,
                                ssError *err)
{
  ssGLContext *c = calloc(1, sizeof *c);
  if (!c) {
    ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
    return NULL;
  }
  c->backend = b;
  c->width = width;
  c->height = height;
  if (b->create(c, err) == SS_OK) return c;
  b->destroy(c);
  free(c);
  return NULL;
}

ssGLContext *ss_glctx_new_backend(const char *key, int width, int height,
                                  ssError *err)
{
  if (width < 1 || height < 1 || width > SS_RENDER_MAX_SIDE ||
      height > SS_RENDER_MAX_SIDE) {
    ss_error_set(err, SS_ERR_VALUE, "", 0,
                 "invalid image size %d x %d (each side must be 1 to %d "
                 "pixels)",
                 width, height, SS_RENDER_MAX_SIDE);
    return NULL;
  }
  const char *from = "the argument";
  if (!key || !*key) {
    key = getenv(SS_GL_ENV);
    from = SS_GL_ENV;
  }
  if (key && *key) {
    /* an explicit choice: that backend or a clear failure */
    const ssGLBackend *b = backend_by_key(key);
    if (!b) {
      if (strcmp(key, "egl") == 0 || strcmp(key, "osmesa") == 0)
        ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0,
                     "%s=%s: this build has no %s backend (configure found no "
                     "%s; see --with-gl)",
                     from, key, key, strcmp(key, "egl") == 0 ? "libegl-dev" : "OSMesa");
      else
        ss_error_set(err, SS_ERR_VALUE, "", 0,
                     "%s=%s: unknown GL backend (use osmesa or egl)", from, key);
      return NULL;
    }
    ssError e;
    memset(&e, 0, sizeof e);
    ssGLContext *c = try_backend(b, width, height, &e);
    if (!c && err) {
      /* say which request failed, unless the message is about the size */
      if (e.code != SS_ERR_VALUE && e.code != SS_ERR_NOMEM)
        ss_error_set(err, e.code, e.file, e.line, "%s=%s: %s", from, key,
                     e.message);
      else
        *err = e;
    }
    return c;
  }

  /* the configured default first, then the others; the default's reason
   * is the one reported when none starts */
  const ssGLBackend *order[SS_GL_NBACKEND];
  size_t n = 0;
  const ssGLBackend *def = backend_by_key(SS_GL_DEFAULT);
  if (def) order[n++] = def;
  for (size_t k = 0; k < SS_GL_NBACKEND; k++)
    if (ss_gl_backends[k] != def) order[n++] = ss_gl_backends[k];
  ssError first;
  memset(&first, 0, sizeof first);
  for (size_t k = 0; k < n; k++) {
    ssError e;
    memset(&e, 0, sizeof e);
    ssGLContext *c = try_backend(order[k], width, height, &e);
    if (c) return c;
    if (k == 0) first = e;
    /* a size the GL cannot render is refused whatever the backend */
    if (e.code == SS_ERR_VALUE || e.code == SS_ERR_NOMEM) break;
  }
  if (err) *err = first;
  return NULL;
}

ssGLContext *ss_glctx_new(int width, int height, ssError *err)
{
  return ss_glctx_new_backend(NULL, width, height, err);
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
  if (gl_current == c) gl_current = NULL;
  free(c);
}
