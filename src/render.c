/* render.c -- off-screen frames of the world and top-down rut maps
 * (DESIGN 6).
 *
 * The 3-D view uses the legacy fixed-function GL pipeline (the fastest path
 * on llvmpipe) with client-side vertex arrays.  A bed is cut into tiles of
 * SS_TILE cells; tiles outside the view frustum are neither updated nor
 * drawn, so a camera following a vehicle over a large bed only pays for
 * what it sees.  Bodies are drawn from their visual geoms (primitives
 * tessellated, meshes from the model's ssMesh), or from their colliders
 * when they have no visual; all of a frame's bodies are placed in world
 * coordinates on the CPU and drawn in one call.  Overlays (caption, colour
 * bar) are drawn in software on the frame read back from GL, with the same
 * code the rut map uses.
 *
 * The rut map needs no GL: it is rasterized in software, one bilinear
 * sample of the vertex values per pixel. */
#include "render.h"

#include "dynamics.h"
#include "mesh.h"
#include "png_io.h"
#include "ss_math.h"

#include <GL/gl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SS_PI 3.14159265358979323846

/* Bed tile size (cells per side) for culling. */
#define SS_TILE 64
/* Most vertices drawn per bed; larger beds are subsampled evenly. */
#define SS_BED_MAX_VERTS (1L << 22)
/* Tessellation of round primitives. */
#define SS_ROUND_SEG 32
#define SS_ROUND_RINGS 16
/* Side of the square drawn for a rigid ground plane: at least this, or
 * several times the scene's extent (m). */
#define SS_PLANE_MIN_SIZE 200.0
/* Visual meshes (mesh_prepare): faces more than 40 degrees apart meet at a
 * sharp edge. */
#define SS_CREASE_COS 0.76604444311897804

/* ---------------------------------------------------------------------- */
/* colour map: a reversed inferno-like ramp, pale yellow -> dark violet,
 * piecewise linear between these control colours (equally spaced in t) */

static const unsigned char cmap_ctrl[][3] = {
  {252, 255, 164}, {246, 214, 68}, {250, 152, 12}, {230, 98, 40},
  {188, 55, 84},   {136, 34, 106}, {87, 16, 110},  {45, 11, 88},
  {20, 11, 52}};
#define SS_CMAP_NCTRL ((int)(sizeof cmap_ctrl / sizeof cmap_ctrl[0]))

void ss_colormap_entry(int k, unsigned char rgb[3])
{
  if (k < 0) k = 0;
  if (k > SS_CMAP_N - 1) k = SS_CMAP_N - 1;
  /* position along the control points, exact at both ends */
  int seg_num = k * (SS_CMAP_NCTRL - 1);
  int seg = seg_num / (SS_CMAP_N - 1);
  if (seg >= SS_CMAP_NCTRL - 1) {
    memcpy(rgb, cmap_ctrl[SS_CMAP_NCTRL - 1], 3);
    return;
  }
  double f = (double)(seg_num - seg * (SS_CMAP_N - 1)) / (double)(SS_CMAP_N - 1);
  for (int c = 0; c < 3; c++) {
    double v = cmap_ctrl[seg][c] + f * (cmap_ctrl[seg + 1][c] - cmap_ctrl[seg][c]);
    rgb[c] = (unsigned char)floor(v + 0.5);
  }
}

int ss_colormap_index(double t)
{
  if (!(t > 0)) return 0;
  if (t >= 1) return SS_CMAP_N - 1;
  return (int)floor(t * (SS_CMAP_N - 1) + 0.5);
}

void ss_colormap(double t, unsigned char rgb[3])
{
  ss_colormap_entry(ss_colormap_index(t), rgb);
}

double ss_colormap_inverse(const unsigned char rgb[3], int *dist2)
{
  int best = 0, bestd = INT32_MAX;
  for (int k = 0; k < SS_CMAP_N; k++) {
    unsigned char c[3];
    ss_colormap_entry(k, c);
    int d = 0;
    for (int i = 0; i < 3; i++) d += (c[i] - rgb[i]) * (c[i] - rgb[i]);
    if (d < bestd) {
      bestd = d;
      best = k;
    }
  }
  if (dist2) *dist2 = bestd;
  return (double)best / (double)(SS_CMAP_N - 1);
}

double ss_nice_ceil(double v)
{
  if (!(v > SS_FULL_SCALE_MIN)) return SS_FULL_SCALE_MIN;
  if (!isfinite(v)) return 1.0;
  double e = pow(10.0, floor(log10(v)));
  static const double steps[] = {1.0, 2.0, 2.5, 5.0, 10.0};
  for (int k = 0; k < 5; k++) {
    /* a relative slack keeps 0.01 (rounding noise) from becoming 0.02 */
    if (steps[k] * e >= v * (1.0 - 1e-12)) return steps[k] * e;
  }
  return 10.0 * e;
}

/* ---------------------------------------------------------------------- */
/* 2-D drawing                                                             */

void ss_img_fill(ssImage *im, int x, int y, int w, int h,
                 const unsigned char rgb[3], double alpha)
{
  int x0 = x < 0 ? 0 : x, y0 = y < 0 ? 0 : y;
  int x1 = x + w > im->w ? im->w : x + w, y1 = y + h > im->h ? im->h : y + h;
  if (x0 >= x1 || y0 >= y1) return;
  unsigned a = alpha >= 1 ? 255u : alpha <= 0 ? 0u : (unsigned)(alpha * 255 + 0.5);
  for (int r = y0; r < y1; r++) {
    unsigned char *p = im->rgba + ((size_t)r * (size_t)im->w + (size_t)x0) * 4;
    for (int c = x0; c < x1; c++, p += 4) {
      if (a == 255) {
        p[0] = rgb[0];
        p[1] = rgb[1];
        p[2] = rgb[2];
      } else {
        for (int k = 0; k < 3; k++)
          p[k] = (unsigned char)((p[k] * (255u - a) + rgb[k] * a + 127u) / 255u);
      }
      p[3] = 255;
    }
  }
}

static const unsigned char ink_rgb[3] = {SS_INK_R, SS_INK_G, SS_INK_B};
static const unsigned char paper_rgb[3] = {SS_PAPER_R, SS_PAPER_G, SS_PAPER_B};

/* Outline one pixel outside the rectangle (x, y, w, h). */
static void img_frame(ssImage *im, int x, int y, int w, int h,
                      const unsigned char rgb[3])
{
  ss_img_fill(im, x - 1, y - 1, w + 2, 1, rgb, 1);
  ss_img_fill(im, x - 1, y + h, w + 2, 1, rgb, 1);
  ss_img_fill(im, x - 1, y, 1, h, rgb, 1);
  ss_img_fill(im, x + w, y, 1, h, rgb, 1);
}

/* Decimals needed to print v exactly enough (at most 4). */
static int decimals_for(double v)
{
  for (int d = 0; d < 4; d++) {
    double s = v * pow(10.0, d);
    if (fabs(s - floor(s + 0.5)) < 1e-6 * (1 + fabs(s))) return d;
  }
  return 4;
}

/* Ticks of a colour bar: n intervals of step (mm) up to full scale. */
static void colorbar_ticks(double fs_mm, int *n, double *step)
{
  double e = pow(10.0, floor(log10(fs_mm)));
  double m = fs_mm / e;
  int k = 2;
  if (fabs(m - 1) < 1e-9 || fabs(m - 10) < 1e-9) k = 5;
  else if (fabs(m - 2) < 1e-9) k = 4;
  else if (fabs(m - 2.5) < 1e-9 || fabs(m - 5) < 1e-9) k = 5;
  *n = k;
  *step = fs_mm / k;
}

static void tick_label(char *buf, size_t len, double v_mm, int dec, int top)
{
  snprintf(buf, len, top ? "%.*f mm" : "%.*f", dec, v_mm);
}

int ss_colorbar_label_width(ssFont *font, double full_scale)
{
  double fs_mm = full_scale * 1000.0;
  int n;
  double step;
  colorbar_ticks(fs_mm, &n, &step);
  int dec = decimals_for(step);
  char buf[64];
  tick_label(buf, sizeof buf, fs_mm, dec, 1);
  return ss_font_width(font, buf) + 6;
}

void ss_draw_colorbar(ssImage *im, ssFont *font, int x, int y, int w, int h,
                      double full_scale, const char *title)
{
  if (w < 1 || h < 2) return;
  for (int r = 0; r < h; r++) {
    unsigned char c[3];
    ss_colormap((double)(h - 1 - r) / (double)(h - 1), c);
    ss_img_fill(im, x, y + r, w, 1, c, 1);
  }
  img_frame(im, x, y, w, h, ink_rgb);
  if (!font) return;

  double fs_mm = full_scale * 1000.0;
  int n;
  double step;
  colorbar_ticks(fs_mm, &n, &step);
  int dec = decimals_for(step);
  int line = ss_font_ascent(font) + ss_font_descent(font);
  /* fewer labels when the bar is short: keep them a line and a half apart */
  while (n > 1 && (double)h / n < 1.5 * line) {
    if (n % 2 == 0) {
      n /= 2;
      step *= 2;
    } else if (n == 5 || n == 3) {
      n = 1;
      step = fs_mm;
    } else {
      n = 1;
      step = fs_mm;
    }
  }
  int asc = ss_font_ascent(font);
  for (int k = 0; k <= n; k++) {
    double v = k == n ? fs_mm : k * step;
    int r = y + h - 1 - (int)floor((double)k / n * (h - 1) + 0.5);
    ss_img_fill(im, x + w + 1, r, 4, 1, ink_rgb, 1);
    char buf[64];
    tick_label(buf, sizeof buf, v, dec, k == n);
    ss_font_draw(font, im, x + w + 7, r + asc / 2 - 1, buf, ink_rgb);
  }
  if (title)
    ss_font_draw(font, im, x, y - ss_font_descent(font) - 4, title, ink_rgb);
}

/* ---------------------------------------------------------------------- */
/* small 4x4 algebra (row-major doubles)                                   */

static void m4_mul(double R[16], const double A[16], const double B[16])
{
  double t[16];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double s = 0;
      for (int k = 0; k < 4; k++) s += A[4 * i + k] * B[4 * k + j];
      t[4 * i + j] = s;
    }
  memcpy(R, t, sizeof t);
}

/* Rigid transform [R p; 0 1] from a row-major rotation and a position. */
static void m4_pose(double M[16], const double R[9], const double p[3])
{
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) M[4 * i + j] = R[3 * i + j];
    M[4 * i + 3] = p[i];
  }
  M[12] = M[13] = M[14] = 0;
  M[15] = 1;
}

/* Column-major copy for glLoadMatrixd / glMultMatrixd. */
static void m4_to_gl(double G[16], const double M[16])
{
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) G[4 * j + i] = M[4 * i + j];
}

static void m4_apply(double out[4], const double M[16], const double p[3])
{
  for (int i = 0; i < 4; i++)
    out[i] = M[4 * i] * p[0] + M[4 * i + 1] * p[1] + M[4 * i + 2] * p[2] + M[4 * i + 3];
}

/* ---------------------------------------------------------------------- */
/* renderer state                                                          */

/* One height map's drawing cache.  The drawn grid is the bed's vertex grid,
 * subsampled by `step` when the bed is larger than SS_BED_MAX_VERTS. */
typedef struct bedCache {
  int nx, ny;          /* the model's vertex counts (to detect changes) */
  int mx, my;          /* drawn vertices along x, y */
  int *ix, *iy;        /* (mx), (my) drawn vertex -> model vertex index */
  float *pos;          /* (mx*my x 3) local x, y and current height */
  float *nrm;          /* (mx*my x 3) */
  unsigned char *col;  /* (mx*my x 4) */
  unsigned *idx;       /* triangle indices, tile after tile */
  int ntx, nty;        /* tiles along x, y */
  long *tile_off;      /* (ntx*nty + 1) first index of each tile */
  double *tile_zlo, *tile_zhi; /* (ntx*nty) undeformed height range */
} bedCache;

/* A unit primitive: positions, normals and triangle indices. */
typedef struct unitMesh {
  int nv, ni;
  float *v, *n;
  unsigned *idx;
} unitMesh;

/* Bodies are drawn in one batch: every primitive's unit mesh is placed in
 * world coordinates on the CPU (a few thousand vertices), which costs far
 * less on llvmpipe than one draw call per primitive. */
typedef struct geomBatch {
  int nv, ni, cap_v, cap_i;
  float *v, *n;
  unsigned char *c;
  unsigned *idx;
} geomBatch;

static void batch_free(geomBatch *b)
{
  free(b->v);
  free(b->n);
  free(b->c);
  free(b->idx);
  memset(b, 0, sizeof *b);
}

struct ssRenderer {
  ssRenderOptions opt;
  int w, h;
  ssGLContext *gl;
  ssFont *font;
  unsigned char *frame;   /* (w*h*4) for ss_render_frame */
  int nbed;
  bedCache *bed;          /* (nhfield) */
  unitMesh box, sphere, cyl;
  geomBatch *solid, *glass; /* bodies of this frame: opaque, translucent */
  int nmesh;              /* model meshes prepared for drawing */
  unitMesh *vmesh;        /* (nmesh) one vertex per triangle corner */
  unsigned char *body_vis; /* (nbody) 1: the body has a visual geom */
  int cap_body;
  /* camera source */
  int cam_mode;           /* 0: automatic, 1: options, 2: model */
  int follow_body;        /* -1: none */
  double follow_ref[3];   /* followed body's initial position */
  double auto_scale;      /* largest sinkage seen (automatic full scale) */
  /* camera of the last frame */
  double mvp[16];         /* projection * view, row-major */
  int have_mvp;
};

ssRenderOptions ss_render_options_default(void)
{
  ssRenderOptions o;
  memset(&o, 0, sizeof o);
  o.width = 1280;
  o.height = 720;
  o.color_mode = SS_COLOR_SINKAGE;
  o.sinkage_max = 0;
  o.camera_given = 0;
  o.camera_pos[0] = 3;
  o.camera_pos[1] = -3;
  o.camera_pos[2] = 2;
  o.camera_fov_deg = 45;
  return o;
}

static void mesh_free(unitMesh *u)
{
  free(u->v);
  free(u->n);
  free(u->idx);
  memset(u, 0, sizeof *u);
}

static int mesh_alloc(unitMesh *u, int nv, int ni)
{
  u->nv = nv;
  u->ni = ni;
  u->v = malloc(sizeof(float) * 3 * (size_t)nv);
  u->n = malloc(sizeof(float) * 3 * (size_t)nv);
  u->idx = malloc(sizeof(unsigned) * (size_t)ni);
  return u->v && u->n && u->idx;
}

static void put3(float *a, int k, double x, double y, double z)
{
  a[3 * k] = (float)x;
  a[3 * k + 1] = (float)y;
  a[3 * k + 2] = (float)z;
}

/* Unit cube [-0.5, 0.5]^3, four vertices per face. */
static int mesh_box(unitMesh *u)
{
  if (!mesh_alloc(u, 24, 36)) return 0;
  static const int axis_sign[6][2] = {{0, 1}, {0, -1}, {1, 1}, {1, -1}, {2, 1}, {2, -1}};
  int v = 0, t = 0;
  for (int f = 0; f < 6; f++) {
    int a = axis_sign[f][0], s = axis_sign[f][1];
    int b = (a + 1) % 3, c = (a + 2) % 3;
    static const double q[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++) {
      double p[3], nn[3] = {0, 0, 0};
      p[a] = 0.5 * s;
      /* keep the winding counter-clockwise seen from outside */
      p[b] = 0.5 * q[k][0] * s;
      p[c] = 0.5 * q[k][1];
      nn[a] = s;
      put3(u->v, v + k, p[0], p[1], p[2]);
      put3(u->n, v + k, nn[0], nn[1], nn[2]);
    }
    unsigned i0 = (unsigned)v;
    unsigned tri[6] = {i0, i0 + 1, i0 + 2, i0, i0 + 2, i0 + 3};
    memcpy(u->idx + t, tri, sizeof tri);
    v += 4;
    t += 6;
  }
  return 1;
}

/* Unit sphere (radius 1), latitude-longitude. */
static int mesh_sphere(unitMesh *u)
{
  int S = SS_ROUND_SEG, R = SS_ROUND_RINGS;
  if (!mesh_alloc(u, (S + 1) * (R + 1), 6 * S * R)) return 0;
  for (int r = 0; r <= R; r++) {
    double th = SS_PI * r / R;
    for (int s = 0; s <= S; s++) {
      double ph = 2 * SS_PI * s / S;
      double x = sin(th) * cos(ph), y = sin(th) * sin(ph), z = cos(th);
      put3(u->v, r * (S + 1) + s, x, y, z);
      put3(u->n, r * (S + 1) + s, x, y, z);
    }
  }
  int t = 0;
  for (int r = 0; r < R; r++)
    for (int s = 0; s < S; s++) {
      unsigned a = (unsigned)(r * (S + 1) + s), b = a + 1;
      unsigned c = a + (unsigned)(S + 1), d = c + 1;
      unsigned tri[6] = {a, c, d, a, d, b};
      memcpy(u->idx + t, tri, sizeof tri);
      t += 6;
    }
  return 1;
}

/* Unit cylinder: radius 1, z from -0.5 to 0.5, with caps. */
static int mesh_cylinder(unitMesh *u)
{
  int S = SS_ROUND_SEG;
  int nv = 2 * (S + 1) + 2 * (S + 1) + 2;
  int ni = 6 * S + 2 * 3 * S;
  if (!mesh_alloc(u, nv, ni)) return 0;
  int v = 0, t = 0;
  /* side */
  for (int s = 0; s <= S; s++) {
    double ph = 2 * SS_PI * s / S, c = cos(ph), sn = sin(ph);
    put3(u->v, v, c, sn, -0.5);
    put3(u->n, v, c, sn, 0);
    put3(u->v, v + 1, c, sn, 0.5);
    put3(u->n, v + 1, c, sn, 0);
    v += 2;
  }
  for (int s = 0; s < S; s++) {
    unsigned a = (unsigned)(2 * s), b = a + 1, c = a + 2, d = a + 3;
    unsigned tri[6] = {a, c, d, a, d, b};
    memcpy(u->idx + t, tri, sizeof tri);
    t += 6;
  }
  /* caps: a centre vertex and a ring each */
  for (int cap = 0; cap < 2; cap++) {
    double z = cap ? 0.5 : -0.5, nz = cap ? 1 : -1;
    unsigned centre = (unsigned)v;
    put3(u->v, v, 0, 0, z);
    put3(u->n, v, 0, 0, nz);
    v++;
    unsigned ring = (unsigned)v;
    for (int s = 0; s <= S; s++) {
      double ph = 2 * SS_PI * s / S;
      put3(u->v, v, cos(ph), sin(ph), z);
      put3(u->n, v, 0, 0, nz);
      v++;
    }
    for (int s = 0; s < S; s++) {
      unsigned a = ring + (unsigned)s, b = a + 1;
      unsigned tri[3] = {centre, cap ? a : b, cap ? b : a};
      memcpy(u->idx + t, tri, sizeof tri);
      t += 3;
    }
  }
  u->nv = v;
  u->ni = t;
  return 1;
}

static void bed_free(bedCache *b)
{
  free(b->ix);
  free(b->iy);
  free(b->pos);
  free(b->nrm);
  free(b->col);
  free(b->idx);
  free(b->tile_off);
  free(b->tile_zlo);
  free(b->tile_zhi);
  memset(b, 0, sizeof *b);
}

/* Build the static parts of a bed's cache (grid, tiles, indices). */
static ssStatus bed_build(bedCache *b, const ssModel *m, int h, ssError *err)
{
  bed_free(b);
  int nx = m->hfield_nx[h], ny = m->hfield_ny[h];
  b->nx = nx;
  b->ny = ny;
  /* subsample beds too large to draw vertex by vertex */
  int step = 1;
  while ((double)((nx - 1) / step + 1) * (double)((ny - 1) / step + 1) >
         (double)SS_BED_MAX_VERTS)
    step++;
  int mx = (nx - 1 + step - 1) / step + 1, my = (ny - 1 + step - 1) / step + 1;
  b->mx = mx;
  b->my = my;
  b->ix = malloc(sizeof(int) * (size_t)mx);
  b->iy = malloc(sizeof(int) * (size_t)my);
  size_t nv = (size_t)mx * (size_t)my;
  b->pos = malloc(sizeof(float) * 3 * nv);
  b->nrm = malloc(sizeof(float) * 3 * nv);
  b->col = malloc(4 * nv);
  b->ntx = (mx - 1 + SS_TILE - 1) / SS_TILE;
  b->nty = (my - 1 + SS_TILE - 1) / SS_TILE;
  size_t nt = (size_t)b->ntx * (size_t)b->nty;
  b->tile_off = malloc(sizeof(long) * (nt + 1));
  b->tile_zlo = malloc(sizeof(double) * nt);
  b->tile_zhi = malloc(sizeof(double) * nt);
  b->idx = malloc(sizeof(unsigned) * 6 * (size_t)(mx - 1) * (size_t)(my - 1));
  if (!b->ix || !b->iy || !b->pos || !b->nrm || !b->col || !b->tile_off ||
      !b->tile_zlo || !b->tile_zhi || !b->idx) {
    bed_free(b);
    return ss_error_set(err, SS_ERR_NOMEM, "", 0,
                        "out of memory for drawing height map '%s'",
                        m->hfield_name[h]);
  }
  for (int k = 0; k < mx; k++) b->ix[k] = k * step < nx - 1 ? k * step : nx - 1;
  for (int k = 0; k < my; k++) b->iy[k] = k * step < ny - 1 ? k * step : ny - 1;

  /* local x, y of every drawn vertex (the formula of DESIGN 2.1) from the
   * bed's centre, which draw_bed puts into the pose in double: single
   * precision then holds the vertices to the bed's size, not to the
   * centre's distance from the origin (a bed centred 100 km out drew
   * over the bodies on it) */
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  double x0 = -0.5 * xs, y0 = -0.5 * ys;
  for (int l = 0; l < my; l++)
    for (int k = 0; k < mx; k++) {
      size_t v = (size_t)l * (size_t)mx + (size_t)k;
      b->pos[3 * v] = (float)(x0 + b->ix[k] * xs / (nx - 1));
      b->pos[3 * v + 1] = (float)(y0 + b->iy[l] * ys / (ny - 1));
      b->pos[3 * v + 2] = 0;
    }

  /* indices tile by tile; undeformed height range per tile */
  const double *hd = m->hfield_data + m->hfield_adr[h];
  long t = 0;
  for (int ty = 0; ty < b->nty; ty++)
    for (int tx = 0; tx < b->ntx; tx++) {
      int tile = ty * b->ntx + tx;
      b->tile_off[tile] = t;
      int k0 = tx * SS_TILE, k1 = k0 + SS_TILE < mx - 1 ? k0 + SS_TILE : mx - 1;
      int l0 = ty * SS_TILE, l1 = l0 + SS_TILE < my - 1 ? l0 + SS_TILE : my - 1;
      double lo = DBL_MAX, hi = -DBL_MAX;
      for (int l = l0; l <= l1; l++)
        for (int k = k0; k <= k1; k++) {
          double z = hd[(size_t)b->iy[l] * (size_t)nx + (size_t)b->ix[k]];
          if (z < lo) lo = z;
          if (z > hi) hi = z;
        }
      b->tile_zlo[tile] = lo;
      b->tile_zhi[tile] = hi;
      for (int l = l0; l < l1; l++)
        for (int k = k0; k < k1; k++) {
          unsigned a = (unsigned)(l * mx + k), bb = a + 1;
          unsigned c = a + (unsigned)mx, d = c + 1;
          b->idx[t++] = a;
          b->idx[t++] = bb;
          b->idx[t++] = d;
          b->idx[t++] = a;
          b->idx[t++] = d;
          b->idx[t++] = c;
        }
    }
  b->tile_off[nt] = t;
  return SS_OK;
}

/* A model mesh ready for batch_add: one vertex per triangle corner.  An
 * ssMesh's vertex normals are smoothed across every edge (assimp's or
 * mesh.c's area-weighted average), which is right for a lathed wheel and
 * wrong at a box's corners.  So a vertex where faces meet at a sharp edge
 * (more than the crease angle, SS_CREASE_COS, apart) gets, at each corner,
 * the area-weighted normal of the faces around it within the crease angle
 * of that corner's face; a vertex with no sharp edge keeps the mesh's own
 * normal.  A flat face thus shows exactly its lit colour, and round shapes
 * stay smooth. */
static int mesh_prepare(unitMesh *u, const ssMesh *me)
{
  memset(u, 0, sizeof *u);
  if (!me || me->ntri <= 0 || me->nvert <= 0 || !me->vert || !me->tri) return 1;
  if (me->ntri > INT_MAX / 3) return 0;
  int nt = me->ntri, nv = me->nvert;
  for (int i = 0; i < 3 * nt; i++)
    if (me->tri[i] < 0 || me->tri[i] >= nv) return 1; /* not drawable */
  double *fn = malloc(sizeof(double) * 3 * (size_t)nt);
  int *start = calloc((size_t)nv + 1, sizeof(int));
  int *adj = malloc(sizeof(int) * 3 * (size_t)nt);
  int ok = fn && start && adj && mesh_alloc(u, 3 * nt, 3 * nt);
  if (ok) {
    /* area-weighted face normals (length = twice the area) */
    for (int t = 0; t < nt; t++) {
      const int *f = me->tri + 3 * t;
      double e1[3], e2[3];
      ss_v3_sub(e1, me->vert + 3 * f[1], me->vert + 3 * f[0]);
      ss_v3_sub(e2, me->vert + 3 * f[2], me->vert + 3 * f[0]);
      ss_v3_cross(fn + 3 * t, e1, e2);
    }
    /* triangles around each vertex */
    for (int i = 0; i < 3 * nt; i++) start[me->tri[i] + 1]++;
    for (int v = 0; v < nv; v++) start[v + 1] += start[v];
    int *fill = malloc(sizeof(int) * (size_t)nv);
    if (!fill) {
      ok = 0;
    } else {
      memcpy(fill, start, sizeof(int) * (size_t)nv);
      for (int i = 0; i < 3 * nt; i++) adj[fill[me->tri[i]]++] = i / 3;
      free(fill);
    }
  }
  if (!ok) {
    free(fn);
    free(start);
    free(adj);
    mesh_free(u);
    return 0;
  }
  for (int t = 0; t < nt; t++) {
    const int *f = me->tri + 3 * t;
    double ft[3];
    ss_v3_copy(ft, fn + 3 * t);
    int has_face = ss_v3_normalize(ft) > 0;
    for (int k = 0; k < 3; k++) {
      int o = 3 * t + k, v = f[k];
      const double *p = me->vert + 3 * v;
      double n[3] = {0, 0, 0};
      int sharp = 0;
      if (has_face) {
        for (int a = start[v]; a < start[v + 1]; a++) {
          const double *g = fn + 3 * adj[a];
          double gl = ss_v3_norm(g);
          if (!(gl > 0)) continue;
          if (ss_v3_dot(g, ft) >= SS_CREASE_COS * gl) ss_v3_add(n, n, g);
          else sharp = 1;
        }
        if (!(ss_v3_normalize(n) > 0)) ss_v3_copy(n, ft);
      }
      const double *mn = me->normal ? me->normal + 3 * v : NULL;
      if (mn && (!has_face || !sharp)) ss_v3_copy(n, mn);
      if (!(ss_v3_norm(n) > 0.5)) ss_v3_set(n, 0, 0, 1);
      put3(u->v, o, p[0], p[1], p[2]);
      put3(u->n, o, n[0], n[1], n[2]);
      u->idx[o] = (unsigned)o;
    }
  }
  free(fn);
  free(start);
  free(adj);
  return 1;
}

/* Prepare every mesh of the model (replacing what was there). */
static ssStatus meshes_build(ssRenderer *r, const ssModel *m, ssError *err)
{
  for (int k = 0; k < r->nmesh; k++) mesh_free(&r->vmesh[k]);
  free(r->vmesh);
  r->vmesh = NULL;
  r->nmesh = 0;
  if (m->nmesh <= 0 || !m->mesh) return SS_OK;
  r->vmesh = calloc((size_t)m->nmesh, sizeof *r->vmesh);
  if (!r->vmesh)
    return ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory for meshes");
  r->nmesh = m->nmesh;
  for (int k = 0; k < m->nmesh; k++)
    if (!mesh_prepare(&r->vmesh[k], m->mesh[k]))
      return ss_error_set(err, SS_ERR_NOMEM, "", 0,
                          "out of memory for drawing mesh %s",
                          m->mesh_path && m->mesh_path[k] ? m->mesh_path[k] : "");
  return SS_OK;
}

/* Which bodies have a visual geom (group bit 2): their collision-only
 * geoms are hidden.  A body without one shows its colliders instead. */
static ssStatus visibility_update(ssRenderer *r, const ssModel *m, ssError *err)
{
  if (m->nbody > r->cap_body) {
    unsigned char *v = realloc(r->body_vis, (size_t)m->nbody);
    if (!v) return ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
    r->body_vis = v;
    r->cap_body = m->nbody;
  }
  if (m->nbody > 0) memset(r->body_vis, 0, (size_t)m->nbody);
  for (int g = 0; g < m->ngeom; g++) {
    int b = m->geom_body[g];
    if (b >= 0 && b < m->nbody && m->geom_group && (m->geom_group[g] & 2))
      r->body_vis[b] = 1;
  }
  return SS_OK;
}

/* Is geom g in this frame?  Its body's system is in the world, its pose
 * is finite, and it is a visual geom, or a collider of a body without
 * visual geoms (see visibility_update). */
static int geom_drawn(const ssRenderer *r, const ssModel *m, const ssData *d,
                      int g)
{
  int b = m->geom_body[g];
  if (b < 0 || b >= m->nbody || b >= r->cap_body) return 0;
  int grp = m->geom_group ? m->geom_group[g] : 3;
  if (!(grp & (r->body_vis[b] ? 2 : 1))) return 0;
  if (m->geom_type[g] == SS_GEOM_MESH) {
    int k = m->geom_mesh ? m->geom_mesh[g] : -1;
    if (k < 0 || k >= r->nmesh || r->vmesh[k].nv == 0) return 0;
  }
  int s = m->body_sys[b];
  if (d->sys_active && !d->sys_active[s]) return 0;
  for (int i = 0; i < 3; i++)
    if (!isfinite(d->geom_xpos[3 * g + i])) return 0;
  for (int i = 0; i < 9; i++)
    if (!isfinite(d->geom_xmat[9 * g + i])) return 0;
  return 1;
}

void ss_render_free(ssRenderer *r)
{
  if (!r) return;
  if (r->gl) ss_glctx_free(r->gl);
  ss_font_free(r->font);
  free(r->frame);
  for (int k = 0; k < r->nbed; k++) bed_free(&r->bed[k]);
  free(r->bed);
  mesh_free(&r->box);
  mesh_free(&r->sphere);
  mesh_free(&r->cyl);
  for (int k = 0; k < r->nmesh; k++) mesh_free(&r->vmesh[k]);
  free(r->vmesh);
  free(r->body_vis);
  if (r->solid) batch_free(r->solid);
  if (r->glass) batch_free(r->glass);
  free(r->solid);
  free(r->glass);
  free(r);
}

/* Label font size of a 3-D frame. */
static int overlay_font_px(int h)
{
  int px = h / 40;
  return px < 10 ? 10 : px > 28 ? 28 : px;
}

ssRenderer *ss_render_new(const ssModel *m, const ssRenderOptions *opt,
                          ssError *err)
{
  ssRenderOptions o = opt ? *opt : ss_render_options_default();
  if (!m) {
    ss_error_set(err, SS_ERR_VALUE, "", 0, "ss_render_new: no model");
    return NULL;
  }
  if (o.width < 1 || o.height < 1 || o.width > SS_RENDER_MAX_SIDE ||
      o.height > SS_RENDER_MAX_SIDE) {
    ss_error_set(err, SS_ERR_VALUE, "", 0,
                 "invalid image size %d x %d: each side must be 1 to %d pixels",
                 o.width, o.height, SS_RENDER_MAX_SIDE);
    return NULL;
  }
  if (o.color_mode < SS_COLOR_SINKAGE || o.color_mode > SS_COLOR_SOIL) {
    ss_error_set(err, SS_ERR_VALUE, "", 0, "invalid colour mode %d",
                 o.color_mode);
    return NULL;
  }
  if (!(o.camera_fov_deg > 0 && o.camera_fov_deg < 180)) {
    ss_error_set(err, SS_ERR_VALUE, "", 0,
                 "invalid camera field of view %g degrees: it must be "
                 "between 0 and 180 (exclusive)", o.camera_fov_deg);
    return NULL;
  }
  if (!isfinite(o.sinkage_max)) {
    ss_error_set(err, SS_ERR_VALUE, "", 0,
                 "colour-bar full scale must be finite (got %g)", o.sinkage_max);
    return NULL;
  }
  ssRenderer *r = calloc(1, sizeof *r);
  if (!r) {
    ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
    return NULL;
  }
  r->opt = o;
  r->w = o.width;
  r->h = o.height;
  r->follow_body = -1;

  /* camera: options, else the scene's <camera>, else automatic */
  const char *follow = NULL;
  if (o.camera_given) {
    r->cam_mode = 1;
    if (o.camera_follow[0]) follow = o.camera_follow;
  } else if (m->camera_given) {
    r->cam_mode = 2;
    follow = o.camera_follow[0] ? o.camera_follow
                                : (m->camera_follow[0] ? m->camera_follow : NULL);
  } else {
    r->cam_mode = 0;
    if (o.camera_follow[0]) follow = o.camera_follow;
  }
  const double *cp = r->cam_mode == 1 ? o.camera_pos : m->camera_pos;
  const double *cl = r->cam_mode == 1 ? o.camera_look_at : m->camera_look_at;
  if (r->cam_mode != 0) {
    if (!ss_camera_valid(cp, cl)) {
      ss_error_set(err, SS_ERR_VALUE, "", 0,
                   "camera position and look_at must be distinct finite points");
      ss_render_free(r);
      return NULL;
    }
  }
  if (follow) {
    int s = ss_model_find_sys(m, follow);
    if (s < 0 || m->sys_nbody[s] < 1) {
      ss_error_set(err, SS_ERR_NOTFOUND, "", 0,
                   "camera follow: no body or articulated system named '%s'",
                   follow);
      ss_render_free(r);
      return NULL;
    }
    r->follow_body = m->sys_bodyadr[s];
    /* the offset is kept relative to where the body starts */
    ssData *d0 = ss_data_new(m);
    if (!d0) {
      ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
      ss_render_free(r);
      return NULL;
    }
    ss_forward(m, d0);
    ss_v3_copy(r->follow_ref, d0->body_xpos + 3 * r->follow_body);
    ss_data_free(d0);
  }

  if (m->nhfield > 0) {
    r->bed = calloc((size_t)m->nhfield, sizeof *r->bed);
    if (!r->bed) {
      ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
      ss_render_free(r);
      return NULL;
    }
    r->nbed = m->nhfield;
    for (int h = 0; h < r->nbed; h++)
      if (bed_build(&r->bed[h], m, h, err) != SS_OK) {
        ss_render_free(r);
        return NULL;
      }
  }
  if (!mesh_box(&r->box) || !mesh_sphere(&r->sphere) || !mesh_cylinder(&r->cyl)) {
    ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
    ss_render_free(r);
    return NULL;
  }
  if (meshes_build(r, m, err) != SS_OK || visibility_update(r, m, err) != SS_OK) {
    ss_render_free(r);
    return NULL;
  }
  r->frame = malloc((size_t)r->w * (size_t)r->h * 4);
  r->solid = calloc(1, sizeof *r->solid);
  r->glass = calloc(1, sizeof *r->glass);
  if (!r->frame || !r->solid || !r->glass) {
    ss_error_set(err, SS_ERR_NOMEM, "", 0,
                 "out of memory for a %d x %d image", r->w, r->h);
    ss_render_free(r);
    return NULL;
  }
  r->font = ss_font_new(overlay_font_px(r->h), err);
  if (!r->font) {
    ss_render_free(r);
    return NULL;
  }
  r->gl = ss_glctx_new(r->w, r->h, err);
  if (!r->gl) {
    ss_render_free(r);
    return NULL;
  }
  return r;
}

/* ---------------------------------------------------------------------- */
/* camera                                                                  */

typedef struct camera {
  double eye[3], target[3];
  double fovy;        /* vertical field of view (rad) */
  double fwd[3], right[3], up[3];
} camera;

static void camera_basis(camera *c)
{
  ss_v3_sub(c->fwd, c->target, c->eye);
  ss_v3_normalize(c->fwd);
  double z[3] = {0, 0, 1};
  ss_v3_cross(c->right, c->fwd, z);
  /* looking straight down: image right is world +x, up is world +y */
  if (ss_v3_norm(c->right) < 1e-9) {
    if (c->fwd[2] < 0) ss_v3_set(c->right, 1, 0, 0);
    else ss_v3_set(c->right, -1, 0, 0);
  }
  ss_v3_normalize(c->right);
  ss_v3_cross(c->up, c->right, c->fwd);
  ss_v3_normalize(c->up);
}

/* Bed rotation (row-major) and position in the world. */
static void bed_pose(const ssModel *m, const ssData *d, int h, double R[9],
                     double p[3])
{
  double q[4];
  memcpy(q, d->hfield_quat + 4 * h, sizeof q);
  ss_quat_normalize(q);
  ss_quat_to_mat(R, q);
  ss_v3_copy(p, d->hfield_pos + 3 * h);
  (void)m;
}

static double soil_value(const ssModel *m, const ssData *d, int h, size_t k,
                         int plastic)
{
  if (!m->hfield_soil[h]) return 0;
  const double *a = plastic ? d->soil_plastic : d->soil_sinkage;
  double v = a ? a[(size_t)m->hfield_adr[h] + k] : 0;
  return v > 0 && isfinite(v) ? v : 0;
}

/* Overview of the first soil bed (else the first height map, else the
 * bodies): seen from its long side, 35 degrees above the horizon, at the
 * distance where its bounding box fills the view. */
static void camera_auto(const ssRenderer *r, const ssModel *m,
                        const ssData *d, double aspect, double fovy, camera *c)
{
  int h = -1;
  for (int k = 0; k < m->nhfield && h < 0; k++)
    if (m->hfield_soil[k]) h = k;
  if (h < 0 && m->nhfield > 0) h = 0;

  double corners[8][3];
  int nc = 0;
  double az[3];
  if (h >= 0) {
    double R[9], p[3];
    bed_pose(m, d, h, R, p);
    double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
    double cx = m->hfield_center[2 * h], cy = m->hfield_center[2 * h + 1];
    int n = m->hfield_nx[h] * m->hfield_ny[h];
    const double *hd = m->hfield_data + m->hfield_adr[h];
    double zlo = DBL_MAX, zhi = -DBL_MAX;
    for (int k = 0; k < n; k++) {
      double z = hd[k] - soil_value(m, d, h, (size_t)k, 0);
      if (z < zlo) zlo = z;
      if (z > zhi) zhi = z;
    }
    for (int k = 0; k < 8; k++) {
      double l[3] = {cx + ((k & 1) ? 0.5 : -0.5) * xs,
                     cy + ((k & 2) ? 0.5 : -0.5) * ys, (k & 4) ? zhi : zlo};
      ss_m3_mulv(corners[k], R, l);
      ss_v3_add(corners[k], corners[k], p);
    }
    nc = 8;
    /* from the -y side of a bed long in x, else from the +x side */
    double s25 = sin(25.0 * SS_PI / 180), c25 = cos(25.0 * SS_PI / 180);
    double al[3];
    if (xs >= ys) ss_v3_set(al, -s25, -c25, 0);
    else ss_v3_set(al, c25, -s25, 0);
    ss_m3_mulv(az, R, al);
  } else {
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    int any = 0;
    for (int g = 0; g < m->ngeom; g++) {
      if (!geom_drawn(r, m, d, g)) continue;
      double rad = ss_dyn_geom_radius(m, g);
      for (int i = 0; i < 3; i++) {
        lo[i] = fmin(lo[i], d->geom_xpos[3 * g + i] - rad);
        hi[i] = fmax(hi[i], d->geom_xpos[3 * g + i] + rad);
      }
      any = 1;
    }
    if (!any)
      for (int i = 0; i < 3; i++) {
        lo[i] = -1;
        hi[i] = 1;
      }
    for (int k = 0; k < 8; k++) {
      corners[k][0] = (k & 1) ? hi[0] : lo[0];
      corners[k][1] = (k & 2) ? hi[1] : lo[1];
      corners[k][2] = (k & 4) ? hi[2] : lo[2];
    }
    nc = 8;
    ss_v3_set(az, -sin(25.0 * SS_PI / 180), -cos(25.0 * SS_PI / 180), 0);
  }
  az[2] = 0;
  if (ss_v3_normalize(az) < 1e-9) ss_v3_set(az, 0, -1, 0);

  double centre[3] = {0, 0, 0};
  for (int k = 0; k < nc; k++) ss_v3_addscl(centre, corners[k], 1.0 / nc);
  double el = 35.0 * SS_PI / 180;
  double dir[3] = {cos(el) * az[0], cos(el) * az[1], sin(el)};
  ss_v3_copy(c->target, centre);
  ss_v3_add(c->eye, centre, dir);
  c->fovy = fovy;
  camera_basis(c);

  /* distance at which every corner lies inside 90 % of the view */
  double tv = tan(0.5 * fovy) * 0.9, th = tv * aspect;
  double dist = 1e-3;
  for (int k = 0; k < nc; k++) {
    double q[3];
    ss_v3_sub(q, corners[k], centre);
    double depth_off = ss_v3_dot(q, c->fwd);
    double need = fmax(fabs(ss_v3_dot(q, c->right)) / th,
                       fabs(ss_v3_dot(q, c->up)) / tv) - depth_off;
    if (need > dist) dist = need;
  }
  ss_v3_copy(c->eye, centre);
  ss_v3_addscl(c->eye, dir, dist);
}

static void camera_for_frame(const ssRenderer *r, const ssModel *m,
                             const ssData *d, camera *c)
{
  double aspect = (double)r->w / (double)r->h;
  double fov_deg = r->cam_mode == 1 ? r->opt.camera_fov_deg
                   : r->cam_mode == 2 ? m->camera_fov_deg
                                      : r->opt.camera_fov_deg;
  /* what ss_render_new and the scene reader accept, (0, 180) degrees */
  if (!(fov_deg > 0 && fov_deg < 180)) fov_deg = 45;
  double fovy = fov_deg * SS_PI / 180;
  if (r->cam_mode == 0) {
    camera_auto(r, m, d, aspect, fovy, c);
  } else {
    const double *cp = r->cam_mode == 1 ? r->opt.camera_pos : m->camera_pos;
    const double *cl = r->cam_mode == 1 ? r->opt.camera_look_at : m->camera_look_at;
    ss_v3_copy(c->eye, cp);
    ss_v3_copy(c->target, cl);
    c->fovy = fovy;
  }
  if (r->follow_body >= 0 && r->follow_body < m->nbody) {
    double off[3];
    ss_v3_sub(off, d->body_xpos + 3 * r->follow_body, r->follow_ref);
    if (isfinite(ss_v3_norm(off))) {
      ss_v3_add(c->eye, c->eye, off);
      ss_v3_add(c->target, c->target, off);
    }
  }
  camera_basis(c);
}

/* ---------------------------------------------------------------------- */
/* the 3-D frame                                                           */

/* Largest value (sinkage or plastic) over all soil beds. */
static double soil_max(const ssModel *m, const ssData *d, int plastic)
{
  double mx = 0;
  for (int h = 0; h < m->nhfield; h++) {
    if (!m->hfield_soil[h]) continue;
    size_t n = (size_t)m->hfield_nx[h] * (size_t)m->hfield_ny[h];
    for (size_t k = 0; k < n; k++) {
      double v = soil_value(m, d, h, k, plastic);
      if (v > mx) mx = v;
    }
  }
  return mx;
}

/* Does the box [lo, hi] (in the frame M maps to clip space) reach into the
 * view volume?  Conservative: only boxes wholly outside one plane fail. */
static int box_visible(const double M[16], const double lo[3], const double hi[3])
{
  int out[6] = {0, 0, 0, 0, 0, 0};
  for (int k = 0; k < 8; k++) {
    double p[3] = {(k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1],
                   (k & 4) ? hi[2] : lo[2]};
    double c[4];
    m4_apply(c, M, p);
    out[0] += c[0] < -c[3];
    out[1] += c[0] > c[3];
    out[2] += c[1] < -c[3];
    out[3] += c[1] > c[3];
    out[4] += c[2] < -c[3];
    out[5] += c[2] > c[3];
  }
  for (int i = 0; i < 6; i++)
    if (out[i] == 8) return 0;
  return 1;
}

/* Current height, normal and colour of the drawn vertices of one tile. */
static void bed_update_tile(bedCache *b, const ssModel *m, const ssData *d,
                            int h, int tile, int mode, double full_scale)
{
  int tx = tile % b->ntx, ty = tile / b->ntx;
  int k0 = tx * SS_TILE, k1 = k0 + SS_TILE < b->mx - 1 ? k0 + SS_TILE : b->mx - 1;
  int l0 = ty * SS_TILE, l1 = l0 + SS_TILE < b->my - 1 ? l0 + SS_TILE : b->my - 1;
  int nx = b->nx, soil = m->hfield_soil[h];
  const double *hd = m->hfield_data + m->hfield_adr[h];
  const double *sk = soil ? d->soil_sinkage + m->hfield_adr[h] : NULL;
  const double *cv = NULL;
  if (soil && mode == SS_COLOR_SINKAGE) cv = d->soil_sinkage + m->hfield_adr[h];
  if (soil && mode == SS_COLOR_PLASTIC) cv = d->soil_plastic + m->hfield_adr[h];
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  unsigned char plain[3];
  if (soil) {
    plain[0] = SS_SOIL_R;
    plain[1] = SS_SOIL_G;
    plain[2] = SS_SOIL_B;
  } else {
    plain[0] = SS_RIGID_R;
    plain[1] = SS_RIGID_G;
    plain[2] = SS_RIGID_B;
  }
  double inv_fs = full_scale > 0 ? 1.0 / full_scale : 0;
  unsigned char lut[SS_CMAP_N][3];
  if (cv)
    for (int k = 0; k < SS_CMAP_N; k++) ss_colormap_entry(k, lut[k]);

#define SURF(i, j) (hd[(size_t)(j) * (size_t)nx + (size_t)(i)] - \
                    (sk ? sk[(size_t)(j) * (size_t)nx + (size_t)(i)] : 0.0))
  for (int l = l0; l <= l1; l++) {
    int j = b->iy[l];
    int jm = l > 0 ? b->iy[l - 1] : j, jp = l < b->my - 1 ? b->iy[l + 1] : j;
    double dy = (jp - jm) * ys / (b->ny - 1);
    for (int k = k0; k <= k1; k++) {
      int i = b->ix[k];
      int im = k > 0 ? b->ix[k - 1] : i, ip = k < b->mx - 1 ? b->ix[k + 1] : i;
      double dx = (ip - im) * xs / (nx - 1);
      size_t v = (size_t)l * (size_t)b->mx + (size_t)k;
      double z = SURF(i, j);
      double gx = dx > 0 ? (SURF(ip, j) - SURF(im, j)) / dx : 0;
      double gy = dy > 0 ? (SURF(i, jp) - SURF(i, jm)) / dy : 0;
      double inv = 1.0 / sqrt(gx * gx + gy * gy + 1.0);
      b->pos[3 * v + 2] = (float)z;
      b->nrm[3 * v] = (float)(-gx * inv);
      b->nrm[3 * v + 1] = (float)(-gy * inv);
      b->nrm[3 * v + 2] = (float)inv;
      unsigned char *c = b->col + 4 * v;
      if (cv) {
        double s = cv[(size_t)j * (size_t)nx + (size_t)i];
        memcpy(c, lut[ss_colormap_index(s * inv_fs)], 3);
      } else {
        memcpy(c, plain, 3);
      }
      c[3] = 255;
    }
  }
#undef SURF
}

static void draw_bed(ssRenderer *r, const ssModel *m, const ssData *d, int h,
                     const double VP[16], const double V[16], double full_scale,
                     double smax_all)
{
  bedCache *b = &r->bed[h];
  double R[9], p[3], B[16], MVP[16], MV[16], G[16];
  bed_pose(m, d, h, R, p);
  /* the vertices are from the bed's centre (bed_build) */
  double cl[3] = {m->hfield_center[2 * h], m->hfield_center[2 * h + 1], 0}, cw[3];
  ss_m3_mulv(cw, R, cl);
  ss_v3_add(p, p, cw);
  m4_pose(B, R, p);
  m4_mul(MVP, VP, B);
  m4_mul(MV, V, B);

  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  double x0 = -0.5 * xs, y0 = -0.5 * ys;
  double sdrop = m->hfield_soil[h] ? smax_all : 0;
  int mode = r->opt.color_mode;

  glMatrixMode(GL_MODELVIEW);
  m4_to_gl(G, MV);
  glLoadMatrixd(G);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glEnableClientState(GL_COLOR_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, b->pos);
  glNormalPointer(GL_FLOAT, 0, b->nrm);
  glColorPointer(4, GL_UNSIGNED_BYTE, 0, b->col);

  /* visible tiles: update their vertices, then draw runs of them at once */
  int nt = b->ntx * b->nty;
  long run_start = -1, run_end = -1;
  for (int t = 0; t < nt; t++) {
    int tx = t % b->ntx, ty = t / b->ntx;
    int k0 = tx * SS_TILE, k1 = k0 + SS_TILE < b->mx - 1 ? k0 + SS_TILE : b->mx - 1;
    int l0 = ty * SS_TILE, l1 = l0 + SS_TILE < b->my - 1 ? l0 + SS_TILE : b->my - 1;
    double lo[3] = {x0 + b->ix[k0] * xs / (b->nx - 1), y0 + b->iy[l0] * ys / (b->ny - 1),
                    b->tile_zlo[t] - sdrop};
    double hi[3] = {x0 + b->ix[k1] * xs / (b->nx - 1), y0 + b->iy[l1] * ys / (b->ny - 1),
                    b->tile_zhi[t]};
    int vis = box_visible(MVP, lo, hi);
    if (vis) {
      bed_update_tile(b, m, d, h, t, mode, full_scale);
      if (run_start < 0) run_start = b->tile_off[t];
      run_end = b->tile_off[t + 1];
    }
    if ((!vis || t == nt - 1) && run_start >= 0) {
      glDrawElements(GL_TRIANGLES, (GLsizei)(run_end - run_start),
                     GL_UNSIGNED_INT, b->idx + run_start);
      run_start = -1;
    }
  }
  glDisableClientState(GL_COLOR_ARRAY);
}

static int batch_reserve(geomBatch *b, int nv, int ni)
{
  if (b->nv + nv > b->cap_v) {
    int cap = 2 * (b->nv + nv);
    float *v = realloc(b->v, sizeof(float) * 3 * (size_t)cap);
    if (v) b->v = v;
    float *n = realloc(b->n, sizeof(float) * 3 * (size_t)cap);
    if (n) b->n = n;
    unsigned char *c = realloc(b->c, 4 * (size_t)cap);
    if (c) b->c = c;
    if (!v || !n || !c) return 0;
    b->cap_v = cap;
  }
  if (b->ni + ni > b->cap_i) {
    int cap = 2 * (b->ni + ni);
    unsigned *idx = realloc(b->idx, sizeof(unsigned) * (size_t)cap);
    if (!idx) return 0;
    b->idx = idx;
    b->cap_i = cap;
  }
  return 1;
}

/* Append unit mesh u scaled by sc, shifted by zshift along its local z,
 * rotated by R and moved to p. */
static int batch_add(geomBatch *b, const unitMesh *u, const double R[9],
                     const double p[3], const double sc[3], double zshift,
                     const unsigned char rgba[4])
{
  if (!batch_reserve(b, u->nv, u->ni)) return 0;
  for (int k = 0; k < u->nv; k++) {
    double l[3] = {u->v[3 * k] * sc[0], u->v[3 * k + 1] * sc[1],
                   u->v[3 * k + 2] * sc[2] + zshift};
    /* normals of a scaled shape: divide by the scale, then renormalize */
    double nl[3] = {u->n[3 * k] / sc[0], u->n[3 * k + 1] / sc[1],
                    u->n[3 * k + 2] / sc[2]};
    double w[3], nw[3];
    ss_m3_mulv(w, R, l);
    ss_m3_mulv(nw, R, nl);
    ss_v3_normalize(nw);
    int o = b->nv + k;
    put3(b->v, o, w[0] + p[0], w[1] + p[1], w[2] + p[2]);
    put3(b->n, o, nw[0], nw[1], nw[2]);
    memcpy(b->c + 4 * o, rgba, 4);
  }
  for (int k = 0; k < u->ni; k++) b->idx[b->ni + k] = u->idx[k] + (unsigned)b->nv;
  b->nv += u->nv;
  b->ni += u->ni;
  return 1;
}

static unsigned char unit_to_byte(double v)
{
  if (!(v > 0)) return 0;
  if (v >= 1) return 255;
  return (unsigned char)floor(v * 255 + 0.5);
}

/* geom g's triangles into b, their vertices from org (the eye: GL's
 * single precision then holds them to the scene's own size, not to its
 * distance from the world origin, where a buggy 100 km out showed its
 * wheels ragged) */
static int batch_geom(const ssRenderer *r, const ssModel *m, const ssData *d,
                      int g, const double org[3], geomBatch *b)
{
  const double *s = m->geom_size + 3 * g;
  const double *R = d->geom_xmat + 9 * g;
  double p[3];
  ss_v3_sub(p, d->geom_xpos + 3 * g, org);
  const double *c = m->geom_rgba + 4 * g;
  unsigned char rgba[4] = {unit_to_byte(c[0]), unit_to_byte(c[1]),
                           unit_to_byte(c[2]), unit_to_byte(c[3] > 0 ? c[3] : 1)};
  /* degenerate sizes would divide normals by zero */
  double s0 = s[0] > 1e-9 ? s[0] : 1e-9, s1 = s[1] > 1e-9 ? s[1] : 1e-9;
  double s2 = s[2] > 1e-9 ? s[2] : 1e-9;
  switch (m->geom_type[g]) {
  case SS_GEOM_BOX: {
    double sc[3] = {s0, s1, s2};
    return batch_add(b, &r->box, R, p, sc, 0, rgba);
  }
  case SS_GEOM_SPHERE: {
    double sc[3] = {s0, s0, s0};
    return batch_add(b, &r->sphere, R, p, sc, 0, rgba);
  }
  case SS_GEOM_CYLINDER: {
    double sc[3] = {s0, s0, s1};
    return batch_add(b, &r->cyl, R, p, sc, 0, rgba);
  }
  case SS_GEOM_CAPSULE: {
    double sc[3] = {s0, s0, s1}, sr[3] = {s0, s0, s0};
    return batch_add(b, &r->cyl, R, p, sc, 0, rgba) &&
           batch_add(b, &r->sphere, R, p, sr, 0.5 * s[1], rgba) &&
           batch_add(b, &r->sphere, R, p, sr, -0.5 * s[1], rgba);
  }
  case SS_GEOM_MESH: {
    /* the mesh's vertices are already in the geom frame, scaled */
    int k = m->geom_mesh[g];
    if (k < 0 || k >= r->nmesh) return 1;
    double one[3] = {1, 1, 1};
    return batch_add(b, &r->vmesh[k], R, p, one, 0, rgba);
  }
  default:
    return 1;
  }
}

static void batch_draw(const geomBatch *b)
{
  if (b->ni == 0) return;
  glVertexPointer(3, GL_FLOAT, 0, b->v);
  glNormalPointer(GL_FLOAT, 0, b->n);
  glColorPointer(4, GL_UNSIGNED_BYTE, 0, b->c);
  glDrawElements(GL_TRIANGLES, b->ni, GL_UNSIGNED_INT, b->idx);
}

/* Scene bounds (world) for the depth range and the size of ground planes. */
static void scene_bounds(const ssRenderer *r, const ssModel *m,
                         const ssData *d, double smax, double lo[3],
                         double hi[3])
{
  for (int i = 0; i < 3; i++) {
    lo[i] = DBL_MAX;
    hi[i] = -DBL_MAX;
  }
  for (int h = 0; h < m->nhfield; h++) {
    double R[9], p[3];
    bed_pose(m, d, h, R, p);
    double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
    double cx = m->hfield_center[2 * h], cy = m->hfield_center[2 * h + 1];
    int n = m->hfield_nx[h] * m->hfield_ny[h];
    const double *hd = m->hfield_data + m->hfield_adr[h];
    double zlo = DBL_MAX, zhi = -DBL_MAX;
    for (int k = 0; k < n; k++) {
      if (hd[k] < zlo) zlo = hd[k];
      if (hd[k] > zhi) zhi = hd[k];
    }
    if (m->hfield_soil[h]) zlo -= smax;
    for (int k = 0; k < 8; k++) {
      double l[3] = {cx + ((k & 1) ? 0.5 : -0.5) * xs,
                     cy + ((k & 2) ? 0.5 : -0.5) * ys, (k & 4) ? zhi : zlo};
      double w[3];
      ss_m3_mulv(w, R, l);
      ss_v3_add(w, w, p);
      for (int i = 0; i < 3; i++) {
        lo[i] = fmin(lo[i], w[i]);
        hi[i] = fmax(hi[i], w[i]);
      }
    }
  }
  for (int g = 0; g < m->ngeom; g++) {
    if (!geom_drawn(r, m, d, g)) continue;
    double rad = ss_dyn_geom_radius(m, g);
    for (int i = 0; i < 3; i++) {
      lo[i] = fmin(lo[i], d->geom_xpos[3 * g + i] - rad);
      hi[i] = fmax(hi[i], d->geom_xpos[3 * g + i] + rad);
    }
  }
  if (lo[0] > hi[0])
    for (int i = 0; i < 3; i++) {
      lo[i] = -1;
      hi[i] = 1;
    }
}

/* Software overlays on the read-back frame: time caption, colour bar. */
static void draw_overlays(ssRenderer *r, const ssModel *m, const ssData *d,
                          unsigned char *rgba, double full_scale)
{
  ssImage im = {rgba, r->w, r->h};
  ssFont *f = r->font;
  int asc = ss_font_ascent(f), desc = ss_font_descent(f);
  int pad = 4, M = SS_OVERLAY_MARGIN + 2;
  char cap[96];
  snprintf(cap, sizeof cap, "t = %.3f s", d->time);
  int cw = ss_font_width(f, cap);
  if (M + cw + 2 * pad < r->w - M && M + asc + desc + 2 * pad < r->h - M) {
    ss_img_fill(&im, M, M, cw + 2 * pad, asc + desc + 2 * pad, paper_rgb, 0.7);
    ss_font_draw(f, &im, M + pad, M + pad + asc, cap, ink_rgb);
  }

  int soil = 0;
  for (int h = 0; h < m->nhfield; h++) soil |= m->hfield_soil[h];
  if (!soil || r->opt.color_mode == SS_COLOR_SOIL) return;
  const char *title = r->opt.color_mode == SS_COLOR_PLASTIC ? "permanent sinkage"
                                                            : "sinkage";
  int line = asc + desc;
  int bar_w = line > 12 ? line : 12;
  int bar_h = r->h / 2;
  int label_w = ss_colorbar_label_width(f, full_scale);
  int title_w = ss_font_width(f, title);
  int body_w = bar_w + 7 + label_w;
  int panel_w = (body_w > title_w ? body_w : title_w) + 2 * pad + 2;
  /* title, half a line for the top label's overhang, bar, half a line */
  int panel_h = 2 * pad + line + line / 2 + 4 + bar_h + line / 2;
  int px = r->w - M - panel_w, py = M;
  if (px <= M || panel_h + 2 * M > r->h || bar_h < 2 * line) return;
  ss_img_fill(&im, px, py, panel_w, panel_h, paper_rgb, 0.7);
  ss_font_draw(f, &im, px + pad, py + pad + asc, title, ink_rgb);
  ss_draw_colorbar(&im, f, px + pad + 1, py + pad + line + line / 2 + 4, bar_w, bar_h,
                   full_scale, NULL);
}

/* GL state of every frame: clear, camera matrices, lights, materials. */
static void gl_frame_state(const ssRenderer *r, const double P[16],
                           const double V[16])
{
  double G[16];
  glViewport(0, 0, r->w, r->h);
  glDisable(GL_DITHER);
  glClearColor(SS_CLEAR_R / 255.0f, SS_CLEAR_G / 255.0f, SS_CLEAR_B / 255.0f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_CULL_FACE);
  glShadeModel(GL_SMOOTH);
  glMatrixMode(GL_PROJECTION);
  m4_to_gl(G, P);
  glLoadMatrixd(G);
  glMatrixMode(GL_MODELVIEW);
  m4_to_gl(G, V);
  glLoadMatrixd(G);

  /* lights in world coordinates: sun high in the sky, horizontal fill */
  GLfloat amb[4] = {(GLfloat)SS_LIGHT_AMBIENT, (GLfloat)SS_LIGHT_AMBIENT,
                    (GLfloat)SS_LIGHT_AMBIENT, 1};
  GLfloat zero[4] = {0, 0, 0, 1};
  GLfloat sun[4] = {(GLfloat)SS_LIGHT_SUN, (GLfloat)SS_LIGHT_SUN,
                    (GLfloat)SS_LIGHT_SUN, 1};
  GLfloat fill[4] = {(GLfloat)SS_LIGHT_FILL, (GLfloat)SS_LIGHT_FILL,
                     (GLfloat)SS_LIGHT_FILL, 1};
  GLfloat sun_dir[4] = {(GLfloat)(-0.25), (GLfloat)(-0.4330127018922193),
                        (GLfloat)SS_LIGHT_SUN_ELEV_COS, 0};
  GLfloat fill_dir[4] = {0.6f, -0.8f, 0, 0};
  glEnable(GL_LIGHTING);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, amb);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_FALSE);
  glEnable(GL_LIGHT0);
  glLightfv(GL_LIGHT0, GL_POSITION, sun_dir);
  glLightfv(GL_LIGHT0, GL_AMBIENT, zero);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, sun);
  glLightfv(GL_LIGHT0, GL_SPECULAR, zero);
  glEnable(GL_LIGHT1);
  glLightfv(GL_LIGHT1, GL_POSITION, fill_dir);
  glLightfv(GL_LIGHT1, GL_AMBIENT, zero);
  glLightfv(GL_LIGHT1, GL_DIFFUSE, fill);
  glLightfv(GL_LIGHT1, GL_SPECULAR, zero);
  glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, zero);
  glMaterialfv(GL_FRONT_AND_BACK, GL_EMISSION, zero);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);

  glDisable(GL_NORMALIZE);
  glDisable(GL_TEXTURE_2D);
}

/* Rigid ground planes as one large square each, pushed back in depth so
 * that a bed at the same height wins; from org, as the bodies' vertices */
static void draw_planes(const ssModel *m, const double ctr_w[3], const double org[3],
                        double half)
{
  const double ctr[3] = {ctr_w[0] - org[0], ctr_w[1] - org[1]};
  if (m->nplane <= 0) return;
  glMatrixMode(GL_MODELVIEW);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(2.0f, 4.0f);
  glColor4ub(SS_PLANE_R, SS_PLANE_G, SS_PLANE_B, 255);
  for (int k = 0; k < m->nplane; k++) {
    double z = m->plane_height[k] - org[2];
    glBegin(GL_TRIANGLES);
    glNormal3d(0, 0, 1);
    glVertex3d(ctr[0] - half, ctr[1] - half, z);
    glVertex3d(ctr[0] + half, ctr[1] - half, z);
    glVertex3d(ctr[0] + half, ctr[1] + half, z);
    glVertex3d(ctr[0] - half, ctr[1] - half, z);
    glVertex3d(ctr[0] + half, ctr[1] + half, z);
    glVertex3d(ctr[0] - half, ctr[1] + half, z);
    glEnd();
  }
  glDisable(GL_POLYGON_OFFSET_FILL);
}

ssStatus ss_render_pixels(ssRenderer *r, const ssModel *m, const ssData *d,
                          unsigned char *rgba, ssError *err)
{
  if (!r || !m || !d || !rgba)
    return ss_error_set(err, SS_ERR_VALUE, "", 0,
                        "ss_render_pixels: NULL argument");
  if (m->nhfield != r->nbed)
    return ss_error_set(err, SS_ERR_STATE, "", 0,
                        "the renderer was made for a different model (%d height "
                        "maps, this one has %d)",
                        r->nbed, m->nhfield);
  for (int h = 0; h < m->nhfield; h++)
    if (r->bed[h].nx != m->hfield_nx[h] || r->bed[h].ny != m->hfield_ny[h]) {
      ssStatus st = bed_build(&r->bed[h], m, h, err);
      if (st != SS_OK) return st;
    }
  ssStatus st;
  if (m->nmesh != r->nmesh && (st = meshes_build(r, m, err)) != SS_OK) return st;
  if ((st = visibility_update(r, m, err)) != SS_OK) return st;
  st = ss_glctx_make_current(r->gl, err);
  if (st != SS_OK) return st;

  /* colour scale: fixed, or the largest value seen so far made nice */
  int plastic = r->opt.color_mode == SS_COLOR_PLASTIC;
  double smax_sink = soil_max(m, d, 0);
  double full_scale = r->opt.sinkage_max;
  if (!(full_scale > 0)) {
    double v = plastic ? soil_max(m, d, 1) : smax_sink;
    if (v > r->auto_scale) r->auto_scale = v;
    full_scale = ss_nice_ceil(r->auto_scale);
  }

  camera c;
  camera_for_frame(r, m, d, &c);

  /* depth range from the scene's extent along the view direction */
  double lo[3], hi[3];
  scene_bounds(r, m, d, smax_sink, lo, hi);
  double ext = 0;
  for (int i = 0; i < 3; i++) ext = fmax(ext, hi[i] - lo[i]);
  double plane_half = 0.5 * fmax(SS_PLANE_MIN_SIZE, 6 * ext);
  double ctr[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0};
  if (m->nplane > 0) {
    lo[0] = fmin(lo[0], ctr[0] - plane_half);
    hi[0] = fmax(hi[0], ctr[0] + plane_half);
    lo[1] = fmin(lo[1], ctr[1] - plane_half);
    hi[1] = fmax(hi[1], ctr[1] + plane_half);
    for (int k = 0; k < m->nplane; k++) {
      lo[2] = fmin(lo[2], m->plane_height[k]);
      hi[2] = fmax(hi[2], m->plane_height[k]);
    }
  }
  double far = 0;
  for (int k = 0; k < 8; k++) {
    double q[3] = {(k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1],
                   (k & 4) ? hi[2] : lo[2]};
    ss_v3_sub(q, q, c.eye);
    far = fmax(far, ss_v3_dot(q, c.fwd));
  }
  far = far * 1.05 + 0.1;
  double near = far * 2e-4;

  /* projection and view (row-major) */
  double aspect = (double)r->w / (double)r->h, fy = 1.0 / tan(0.5 * c.fovy);
  double P[16] = {fy / aspect, 0, 0, 0,
                  0, fy, 0, 0,
                  0, 0, (far + near) / (near - far), 2 * far * near / (near - far),
                  0, 0, -1, 0};
  double V[16] = {c.right[0], c.right[1], c.right[2], -ss_v3_dot(c.right, c.eye),
                  c.up[0], c.up[1], c.up[2], -ss_v3_dot(c.up, c.eye),
                  -c.fwd[0], -c.fwd[1], -c.fwd[2], ss_v3_dot(c.fwd, c.eye),
                  0, 0, 0, 1};
  /* the view of what is drawn from the eye (the bodies and ground
   * planes: batch_geom): V less its translation */
  double Ve[16];
  memcpy(Ve, V, sizeof Ve);
  Ve[3] = Ve[7] = Ve[11] = 0;
  double VP[16], G[16];
  m4_mul(VP, P, V);
  memcpy(r->mvp, VP, sizeof VP);
  r->have_mvp = 1;

  gl_frame_state(r, P, V);
  glMatrixMode(GL_MODELVIEW);
  m4_to_gl(G, Ve);
  glLoadMatrixd(G);
  draw_planes(m, ctr, c.eye, plane_half);

  /* beds */
  for (int h = 0; h < m->nhfield; h++)
    draw_bed(r, m, d, h, VP, V, full_scale, smax_sink);

  /* bodies: opaque first, then translucent ones blended over them */
  r->solid->nv = r->solid->ni = 0;
  r->glass->nv = r->glass->ni = 0;
  for (int g = 0; g < m->ngeom; g++) {
    if (!geom_drawn(r, m, d, g)) continue;
    double a = m->geom_rgba[4 * g + 3];
    if (!batch_geom(r, m, d, g, c.eye, a > 0 && a < 1 ? r->glass : r->solid))
      return ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory for bodies");
  }
  glMatrixMode(GL_MODELVIEW);
  m4_to_gl(G, Ve);
  glLoadMatrixd(G);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glEnableClientState(GL_COLOR_ARRAY);
  batch_draw(r->solid);
  if (r->glass->ni > 0) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    batch_draw(r->glass);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
  glDisableClientState(GL_VERTEX_ARRAY);
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_COLOR_ARRAY);

  GLenum glerr = glGetError();
  if (glerr != GL_NO_ERROR)
    return ss_error_set(err, SS_ERR_STATE, "", 0, "GL error 0x%x while drawing",
                        (unsigned)glerr);
  st = ss_glctx_read_rgba(r->gl, rgba, err);
  if (st != SS_OK) return st;
  /* frames are opaque whatever blending did to destination alpha */
  size_t np = (size_t)r->w * (size_t)r->h;
  for (size_t k = 0; k < np; k++) rgba[4 * k + 3] = 255;
  draw_overlays(r, m, d, rgba, full_scale);
  return SS_OK;
}

ssStatus ss_render_frame(ssRenderer *r, const ssModel *m, const ssData *d,
                         const char *png_path, ssError *err)
{
  if (!r)
    return ss_error_set(err, SS_ERR_VALUE, "", 0, "ss_render_frame: no renderer");
  ssStatus st = ss_render_pixels(r, m, d, r->frame, err);
  if (st != SS_OK) return st;
  return ss_png_write_rgba(png_path, r->w, r->h, r->frame, err);
}

const char *ss_render_backend_name(const ssRenderer *r)
{
  return r ? ss_glctx_backend_name(r->gl) : "none";
}

/* Continuous pixel coordinates of world point p in the last frame (pixel
 * (c, r) covers [c, c+1) x [r, r+1), row 0 at the top); 0 if p is behind
 * the camera or no frame has been drawn. */
int ss_render_project(const ssRenderer *r, const double p[3], double *col,
                      double *row)
{
  if (!r || !r->have_mvp) return 0;
  double c[4];
  m4_apply(c, r->mvp, p);
  if (!(c[3] > 0)) return 0;
  *col = (c[0] / c[3] + 1) * 0.5 * r->w;
  *row = (1 - c[1] / c[3]) * 0.5 * r->h;
  return 1;
}

/* ---------------------------------------------------------------------- */
/* rut map                                                                 */

/* Largest 1, 2 or 5 x 10^k not above v. */
static double nice_floor(double v)
{
  double e = pow(10.0, floor(log10(v)));
  double m = v / e;
  return (m >= 5 ? 5 : m >= 2 ? 2 : 1) * e;
}

int ss_rut_map_layout(int width, int height, double x_size, double y_size,
                      ssRutMapLayout *lay)
{
  memset(lay, 0, sizeof *lay);
  if (width < SS_RUT_MAP_MIN_WIDTH || height < SS_RUT_MAP_MIN_SIDE ||
      !(x_size > 0) || !(y_size > 0) || !isfinite(x_size) || !isfinite(y_size))
    return -1;
  int fp = height / 36 < width / 50 ? height / 36 : width / 50;
  fp = fp < 9 ? 9 : fp > 32 ? 32 : fp;
  int margin = fp / 2 > 4 ? fp / 2 : 4;
  int top = margin + (fp * 3) / 2;            /* title band */
  int bar_w = fp;
  int gap = fp;
  int label_w = (fp * 9) / 2;                 /* room for "12.5 mm" */
  int right = gap + bar_w + 8 + label_w + margin;
  int thick = fp / 4 > 3 ? fp / 4 : 3;        /* scale bar thickness */
  int bottom = (fp * 2) / 3 + (thick > fp ? thick : fp) + margin;

  int ax = margin, ay = top;
  int aw = width - ax - right, ah = height - ay - bottom;
  if (aw < 8 || ah < 8) return -1;
  int mw, mh;
  if ((double)aw / ah > x_size / y_size) {
    mh = ah;
    mw = (int)floor(ah * x_size / y_size + 0.5);
  } else {
    mw = aw;
    mh = (int)floor(aw * y_size / x_size + 0.5);
  }
  if (mw < 1) mw = 1;
  if (mh < 1) mh = 1;
  lay->map_w = mw;
  lay->map_h = mh;
  lay->map_x = ax + (aw - mw) / 2;
  lay->map_y = ay + (ah - mh) / 2;

  /* the bar beside the map, at least eight lines tall where room allows */
  lay->bar_w = bar_w;
  lay->bar_x = lay->map_x + mw + gap;
  int bh = mh > 8 * fp ? mh : 8 * fp;
  if (bh > ah) bh = ah;
  lay->bar_h = bh;
  lay->bar_y = lay->map_y + (mh - bh) / 2;
  if (lay->bar_y < ay) lay->bar_y = ay;
  if (lay->bar_y + bh > ay + ah) lay->bar_y = ay + ah - bh;

  /* the metre scale under the map, about a quarter of its width */
  lay->scale_m = nice_floor(0.25 * x_size);
  lay->scale_len = (int)floor(lay->scale_m / x_size * mw + 0.5);
  if (lay->scale_len < 1) lay->scale_len = 1;
  lay->scale_x = lay->map_x;
  lay->scale_y = lay->map_y + mh + (fp * 2) / 3;
  lay->title_x = margin;
  lay->title_y = margin + fp;
  lay->font_px = fp;
  return 0;
}

void ss_rut_map_pixel(const ssRutMapLayout *lay, double u, double v, int *col,
                      int *row)
{
  *col = lay->map_x + (int)floor(u * lay->map_w);
  *row = lay->map_y + (int)floor((1 - v) * lay->map_h);
  if (*col >= lay->map_x + lay->map_w) *col = lay->map_x + lay->map_w - 1;
  if (*row >= lay->map_y + lay->map_h) *row = lay->map_y + lay->map_h - 1;
  if (*col < lay->map_x) *col = lay->map_x;
  if (*row < lay->map_y) *row = lay->map_y;
}

/* Format a length in metres for the scale label. */
static void metres_label(char *buf, size_t len, double m)
{
  if (m >= 1) snprintf(buf, len, "%g m", m);
  else if (m >= 0.01) snprintf(buf, len, "%g cm", m * 100);
  else snprintf(buf, len, "%g mm", m * 1000);
}

/* What a rut map of bed hfield (-1: the first soil bed) at width x height
 * needs before any pixel: the bed (*h), its layout (*L) and the label
 * font (*font, NULL where font is NULL: the check alone) */
static ssStatus rut_map_setup(const ssModel *m, int hfield, int width, int height,
                              const char *png_path, int *hout, ssRutMapLayout *Lout,
                              ssFont **font, ssError *err)
{
  int h = hfield;
  if (h < 0) {
    for (int k = 0; k < m->nhfield && h < 0; k++)
      if (m->hfield_soil[k]) h = k;
    if (h < 0)
      return ss_error_set(err, SS_ERR_NOTFOUND, png_path ? png_path : "", 0,
                          "rut map: the world has no soil bed");
  } else if (h >= m->nhfield) {
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "rut map: no height map %d (the world has %d)", h,
                        m->nhfield);
  } else if (!m->hfield_soil[h]) {
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "rut map: height map '%s' is rigid, not a soil bed",
                        m->hfield_name[h]);
  }
  if (width > SS_RENDER_MAX_SIDE || height > SS_RENDER_MAX_SIDE)
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "invalid rut map size %d x %d: %d to %d pixels wide, "
                        "%d to %d high",
                        width, height, SS_RUT_MAP_MIN_WIDTH, SS_RENDER_MAX_SIDE,
                        SS_RUT_MAP_MIN_SIDE, SS_RENDER_MAX_SIDE);
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  if (ss_rut_map_layout(width, height, xs, ys, Lout) != 0)
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "invalid rut map size %d x %d: %d to %d pixels wide, "
                        "%d to %d high",
                        width, height, SS_RUT_MAP_MIN_WIDTH, SS_RENDER_MAX_SIDE,
                        SS_RUT_MAP_MIN_SIDE, SS_RENDER_MAX_SIDE);
  ssFont *f = ss_font_new(Lout->font_px, err);
  if (!f) return err ? err->code : SS_ERR_IO;
  if (font)
    *font = f;
  else
    ss_font_free(f);
  *hout = h;
  return SS_OK;
}

/* (render.h) */
ssStatus ss_render_rut_map_check(const ssModel *m, int hfield, int width, int height,
                                 const char *png_path, ssError *err)
{
  if (!m)
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "ss_render_rut_map_check: no model");
  int h = -1;
  ssRutMapLayout L;
  return rut_map_setup(m, hfield, width, height, png_path, &h, &L, NULL, err);
}

/* The rut map, written to png_path or, when af is given, into it (left
 * open for the caller to commit). */
static ssStatus rut_map(const ssModel *m, const ssData *d, int hfield,
                        int plastic, int width, int height,
                        const char *png_path, ssAtomicFile *af, ssError *err)
{
  if (!m || !d)
    return ss_error_set(err, SS_ERR_VALUE, png_path ? png_path : "", 0,
                        "ss_render_rut_map: no model or data");
  int h = -1;
  ssRutMapLayout L;
  ssFont *font = NULL;
  ssStatus st0 = rut_map_setup(m, hfield, width, height, png_path, &h, &L, &font, err);
  if (st0) return st0;

  int nx = m->hfield_nx[h], ny = m->hfield_ny[h];
  size_t n = (size_t)nx * (size_t)ny;
  double vmax = 0;
  for (size_t k = 0; k < n; k++) vmax = fmax(vmax, soil_value(m, d, h, k, plastic));
  double fs = ss_nice_ceil(vmax);

  unsigned char *px = malloc((size_t)width * (size_t)height * 4);
  if (!px) {
    ss_font_free(font);
    return ss_error_set(err, SS_ERR_NOMEM, png_path ? png_path : "", 0,
                        "out of memory for a %d x %d rut map", width, height);
  }
  ssImage im = {px, width, height};
  ss_img_fill(&im, 0, 0, width, height, paper_rgb, 1);

  /* the map: one bilinear sample per pixel centre */
  unsigned char lut[SS_CMAP_N][3];
  for (int k = 0; k < SS_CMAP_N; k++) ss_colormap_entry(k, lut[k]);
  const double *vals = (plastic ? d->soil_plastic : d->soil_sinkage) + m->hfield_adr[h];
  for (int row = 0; row < L.map_h; row++) {
    double v = 1.0 - (row + 0.5) / L.map_h;
    double gy = v * (ny - 1);
    int j = (int)floor(gy);
    if (j > ny - 2) j = ny - 2;
    if (j < 0) j = 0;
    double fy = gy - j;
    unsigned char *out = px + ((size_t)(L.map_y + row) * (size_t)width + (size_t)L.map_x) * 4;
    for (int col = 0; col < L.map_w; col++, out += 4) {
      double u = (col + 0.5) / L.map_w;
      double gx = u * (nx - 1);
      int i = (int)floor(gx);
      if (i > nx - 2) i = nx - 2;
      if (i < 0) i = 0;
      double fx = gx - i;
      size_t a = (size_t)j * (size_t)nx + (size_t)i;
      double s00 = vals[a], s10 = vals[a + 1], s01 = vals[a + nx], s11 = vals[a + nx + 1];
      double s = (1 - fy) * ((1 - fx) * s00 + fx * s10) + fy * ((1 - fx) * s01 + fx * s11);
      const unsigned char *c = lut[ss_colormap_index(s / fs)];
      out[0] = c[0];
      out[1] = c[1];
      out[2] = c[2];
      out[3] = 255;
    }
  }
  img_frame(&im, L.map_x, L.map_y, L.map_w, L.map_h, ink_rgb);

  /* title, colour bar, metre scale */
  /* the longest title that ends before the colour bar's labels, whose
   * top one reaches up into the title's line (a long one ran over it) */
  char title[4][256];
  const char *what = plastic ? "permanent sinkage" : "sinkage";
  snprintf(title[0], sizeof title[0], "%s: %s, max %.2f mm, t = %.3f s",
           m->hfield_name[h] ? m->hfield_name[h] : "bed", what, vmax * 1000.0,
           d->time);
  snprintf(title[1], sizeof title[1], "%s, max %.2f mm, t = %.3f s", what,
           vmax * 1000.0, d->time);
  snprintf(title[2], sizeof title[2], "%s, max %.2f mm", what, vmax * 1000.0);
  snprintf(title[3], sizeof title[3], "max %.2f mm", vmax * 1000.0);
  int room = L.bar_x + L.bar_w + 7 - L.font_px / 2 - L.title_x, pick = 0;
  while (pick < 3 && ss_font_width(font, title[pick]) > room) pick++;
  ss_font_draw(font, &im, L.title_x, L.title_y, title[pick], ink_rgb);
  ss_draw_colorbar(&im, font, L.bar_x, L.bar_y, L.bar_w, L.bar_h, fs, NULL);
  int thick = L.font_px / 4 > 3 ? L.font_px / 4 : 3;
  ss_img_fill(&im, L.scale_x, L.scale_y, L.scale_len, thick, ink_rgb, 1);
  ss_img_fill(&im, L.scale_x, L.scale_y - thick, 1, 3 * thick, ink_rgb, 1);
  ss_img_fill(&im, L.scale_x + L.scale_len - 1, L.scale_y - thick, 1, 3 * thick,
              ink_rgb, 1);
  char sl[32];
  metres_label(sl, sizeof sl, L.scale_m);
  ss_font_draw(font, &im, L.scale_x + L.scale_len + L.font_px / 2,
               L.scale_y + thick / 2 + ss_font_ascent(font) / 2 - 1, sl, ink_rgb);
  ss_font_free(font);

  ssStatus st = af ? ss_png_write_rgba_to(af, width, height, px, err)
                   : ss_png_write_rgba(png_path, width, height, px, err);
  free(px);
  return st;
}

ssStatus ss_render_rut_map(const ssModel *m, const ssData *d, int hfield,
                           int plastic, int width, int height,
                           const char *png_path, ssError *err)
{
  return rut_map(m, d, hfield, plastic, width, height, png_path, NULL, err);
}

ssStatus ss_render_rut_map_to(const ssModel *m, const ssData *d, int hfield,
                              int plastic, int width, int height,
                              ssAtomicFile *af, ssError *err)
{
  if (!af || !af->fp)
    return ss_error_set(err, SS_ERR_STATE, af ? af->path : "", 0,
                        "rut map output not open");
  return rut_map(m, d, hfield, plastic, width, height, af->path, af, err);
}
