/* render.h -- internals of the off-screen renderer (DESIGN 6), shared by
 * render.c, render_context.c, render_font.c and tests/test_render.c.
 *
 * What a test can rely on (all documented here, checked in test_render.c):
 *  - colour map: sinkage fraction t = s / full_scale in [0, 1] -> one of
 *    SS_CMAP_N colours; t = 0 is exactly SS_CMAP_ZERO_* (pale yellow), t = 1
 *    exactly SS_CMAP_DEEP_* (dark violet); lightness falls monotonically in
 *    between (a reversed inferno-like map), so ss_colormap_inverse() can read
 *    a value back from a pixel;
 *  - lighting of the 3-D view: a "sun" 30 degrees from the zenith and a
 *    horizontal fill light, scaled so that a surface whose normal points
 *    straight up (world +Z) is lit with intensity exactly 1 and shows its
 *    own colour (a box's top face, a flat bed, a flat rut floor); slopes
 *    facing the sun are brighter (clamped), slopes facing away darker;
 *  - bodies: a geom is drawn when it is a visual (geom_group bit 2), or a
 *    collider (bit 1) of a body that has no visual geom at all; primitives
 *    are tessellated, SS_GEOM_MESH geoms drawn from m->mesh with normals
 *    that are smooth except across edges sharper than 40 degrees, so a
 *    mesh's flat face pointing up shows exactly its geom_rgba colour;
 *  - overlays (caption, colour bar) never touch the outer SS_OVERLAY_MARGIN
 *    pixels of a 3-D frame, so the image corners show the clear colour (or
 *    the scene);
 *  - the rut map's geometry comes from ss_rut_map_layout().
 */
#ifndef SS_RENDER_H
#define SS_RENDER_H

#include "soilsim.h"

/* ---------------------------------------------------------------------- */
/* colours                                                                 */

/* Background of the 3-D view (light blue-grey sky). */
#define SS_CLEAR_R 200
#define SS_CLEAR_G 214
#define SS_CLEAR_B 230
/* Plain soil (SS_COLOR_SOIL) and rigid height maps. */
#define SS_SOIL_R 186
#define SS_SOIL_G 160
#define SS_SOIL_B 122
#define SS_RIGID_R 150
#define SS_RIGID_G 150
#define SS_RIGID_B 150
/* Rigid ground planes. */
#define SS_PLANE_R 128
#define SS_PLANE_G 128
#define SS_PLANE_B 128
/* Rut map background and text. */
#define SS_PAPER_R 255
#define SS_PAPER_G 255
#define SS_PAPER_B 255
#define SS_INK_R 25
#define SS_INK_G 25
#define SS_INK_B 25

/* Lighting of the 3-D view: intensity = ambient + sun max(n.L, 0) +
 * fill max(n.F, 0) with L = (-0.25, -0.433, 0.866) (30 degrees from +Z)
 * and F = (0.6, -0.8, 0) (horizontal), so that n = +Z gets
 * SS_LIGHT_AMBIENT + SS_LIGHT_SUN cos 30 = 1. */
#define SS_LIGHT_AMBIENT 0.35
#define SS_LIGHT_SUN_ELEV_COS 0.86602540378443865 /* cos 30 degrees */
#define SS_LIGHT_SUN ((1.0 - SS_LIGHT_AMBIENT) / SS_LIGHT_SUN_ELEV_COS)
#define SS_LIGHT_FILL 0.25

/* Overlay-free border of a 3-D frame (pixels). */
#define SS_OVERLAY_MARGIN 8

/* Largest image side the renderer accepts (pixels). */
#define SS_RENDER_MAX_SIDE 16384

/* ---------------------------------------------------------------------- */
/* colour map                                                              */

#define SS_CMAP_N 256
/* t = 0: zero sinkage. */
#define SS_CMAP_ZERO_R 252
#define SS_CMAP_ZERO_G 255
#define SS_CMAP_ZERO_B 164
/* t = 1: full scale and deeper. */
#define SS_CMAP_DEEP_R 20
#define SS_CMAP_DEEP_G 11
#define SS_CMAP_DEEP_B 52

/* Index of fraction t: round(t * (SS_CMAP_N - 1)), t clamped to [0, 1]
 * (NaN counts as 0). */
int ss_colormap_index(double t);
/* Colour of fraction t (rgb[3]). */
void ss_colormap(double t, unsigned char rgb[3]);
/* Colour of entry k (0 .. SS_CMAP_N - 1). */
void ss_colormap_entry(int k, unsigned char rgb[3]);
/* The fraction t = k / (SS_CMAP_N - 1) of the entry nearest to rgb (in RGB
 * distance); *dist2 (may be NULL) receives the squared distance, 0 for a
 * colour taken straight from the map. */
double ss_colormap_inverse(const unsigned char rgb[3], int *dist2);

/* Full scale of the 3-D view's colour bar: ssRenderOptions.sinkage_max when
 * > 0, else ss_nice_ceil of the largest value this renderer has drawn so far
 * (so a sequence of frames keeps one scale until the ruts outgrow it; the
 * same state drawn twice gives the same pixels). */

/* Automatic full scale: the smallest 1, 2, 2.5 or 5 x 10^k that is >= v
 * (v > 0); at least SS_FULL_SCALE_MIN. */
#define SS_FULL_SCALE_MIN 1e-4
double ss_nice_ceil(double v);

/* Where world point p fell in the renderer's last frame: continuous pixel
 * coordinates (pixel (c, r) covers [c, c+1) x [r, r+1), row 0 at the top).
 * Returns 0 when p is behind the camera or nothing has been drawn yet.
 * With the camera looking straight down, image right is world +x and image
 * up is world +y. */
int ss_render_project(const ssRenderer *r, const double p[3], double *col,
                      double *row);
/* The GL backend a renderer draws with: "OSMesa" or "EGL". */
const char *ss_render_backend_name(const ssRenderer *r);

/* ---------------------------------------------------------------------- */
/* GL context (render_context.c): OSMesa, or EGL surfaceless (EGL_MESA_
 * platform_surfaceless, a context without surfaces drawing into a
 * framebuffer object) where configure found libegl-dev.  The environment
 * variable SOILSIM_GL=osmesa|egl picks one (and only that one is tried);
 * otherwise the configure default (--with-gl) is tried first, then the
 * other.  Both give the same pixels (Mesa's llvmpipe either way). */

typedef struct ssGLContext ssGLContext;

#define SS_GL_ENV "SOILSIM_GL"
/* the environment variable naming the label font file (ss_font_new): set,
 * that file alone is tried; unset, the configured font, then DejaVu Sans */
#define SS_FONT_ENV "SOILSIM_FONT"

/* A context rendering width x height pixels (1 .. SS_RENDER_MAX_SIDE),
 * current on return.  NULL with err filled on failure. */
ssGLContext *ss_glctx_new(int width, int height, ssError *err);
/* The same with the backend named ("osmesa" or "egl"; NULL or "" = as
 * ss_glctx_new: SOILSIM_GL, else the default, else the other). */
ssGLContext *ss_glctx_new_backend(const char *key, int width, int height,
                                  ssError *err);
/* 1 if this build contains the backend ("osmesa", "egl"). */
int ss_glctx_backend_built(const char *key);
/* The configure default ("osmesa" or "egl"). */
const char *ss_glctx_default_backend(void);
ssStatus ss_glctx_make_current(ssGLContext *c, ssError *err);
/* glFinish, then copy the frame (width*height*4, row 0 at the top). */
ssStatus ss_glctx_read_rgba(ssGLContext *c, unsigned char *rgba, ssError *err);
/* "OSMesa" or "EGL" ("none" for NULL). */
const char *ss_glctx_backend_name(const ssGLContext *c);
void ss_glctx_free(ssGLContext *c); /* accepts NULL */

/* ---------------------------------------------------------------------- */
/* 2-D drawing into RGBA images (overlays and the rut map)                 */

typedef struct ssImage {
  unsigned char *rgba; /* w*h*4, row 0 at the top */
  int w, h;
} ssImage;

/* Blend rgb over the rectangle with opacity alpha in [0, 1] (clipped). */
void ss_img_fill(ssImage *im, int x, int y, int w, int h,
                 const unsigned char rgb[3], double alpha);

/* ---------------------------------------------------------------------- */
/* text (render_font.c, FreeType)                                          */

typedef struct ssFont ssFont;

/* Load the label font (SS_FONT_PATH from config.h, else DejaVu Sans) at a
 * pixel size; NULL with err filled when no font can be loaded. */
ssFont *ss_font_new(int pixel_size, ssError *err);
void ss_font_free(ssFont *f); /* accepts NULL */
/* Advance width of a UTF-8 string (pixels). */
int ss_font_width(ssFont *f, const char *text);
/* Ascent and descent (both >= 0) of the face at this size (pixels). */
int ss_font_ascent(const ssFont *f);
int ss_font_descent(const ssFont *f);
/* Draw anti-aliased text with its baseline at row y, starting at column x. */
void ss_font_draw(ssFont *f, ssImage *im, int x, int y, const char *text,
                  const unsigned char rgb[3]);

/* ---------------------------------------------------------------------- */
/* colour bar (shared by the 3-D view and the rut map)                     */

/* Draw a vertical colour bar in the rectangle (x, y, w, h): the top row has
 * t = 1 (full_scale), the bottom row t = 0; row r shows
 * ss_colormap((y + h - 1 - r) / (h - 1)).  Tick labels in millimetres go to
 * the right of the bar, the title above it. */
void ss_draw_colorbar(ssImage *im, ssFont *font, int x, int y, int w, int h,
                      double full_scale, const char *title);
/* Width in pixels that labels of this full scale need right of the bar. */
int ss_colorbar_label_width(ssFont *font, double full_scale);

/* ---------------------------------------------------------------------- */
/* rut map layout (ss_render_rut_map)                                      */

/* Where everything sits in a rut map of width x height pixels.
 * The map shows the bed seen from above in its own frame: local +x to the
 * right, local +y up.  Pixel (col, row) with map_x <= col < map_x + map_w,
 * map_y <= row < map_y + map_h shows the bed point at fractions
 *   u = (col - map_x + 0.5) / map_w,   v = 1 - (row - map_y + 0.5) / map_h
 * of its extent, i.e. x = center_x - x_size/2 + u x_size (likewise y), its
 * value bilinearly interpolated from the four surrounding vertices.  The
 * map keeps the bed's aspect ratio (square metres stay square, to within a
 * pixel) and is centred in the space left by the title above, the colour bar
 * to the right and the metre scale below.  Everything outside the map and
 * the overlays is SS_PAPER (white). */
typedef struct ssRutMapLayout {
  int map_x, map_y, map_w, map_h; /* the bed rectangle (pixels) */
  int bar_x, bar_y, bar_w, bar_h; /* colour bar: top row = full scale */
  int scale_x, scale_y;           /* metre scale: left end, top row */
  int scale_len;                  /* its length (pixels) */
  double scale_m;                 /* its length (m): 1, 2 or 5 x 10^k */
  int title_x, title_y;           /* title baseline start */
  int font_px;                    /* label font size (pixels) */
} ssRutMapLayout;

/* Fill *lay for an image of width x height pixels showing a bed of
 * x_size x y_size metres.  Returns 0, or -1 when the image is too small to
 * hold a map (under SS_RUT_MAP_MIN_WIDTH pixels wide or SS_RUT_MAP_MIN_SIDE
 * high, soilsim.h; every size from those up has room, test_render). */
int ss_rut_map_layout(int width, int height, double x_size, double y_size,
                      ssRutMapLayout *lay);
/* Pixel showing bed fractions (u, v) in [0, 1] (see above). */
void ss_rut_map_pixel(const ssRutMapLayout *lay, double u, double v, int *col,
                      int *row);

/* Rut map full scale: the largest value on the bed rounded up with
 * ss_nice_ceil (so 8.2 mm gives a 0-10 mm bar); SS_FULL_SCALE_MIN when the
 * bed is untouched. */

#endif /* SS_RENDER_H */
