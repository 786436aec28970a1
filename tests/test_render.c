/* test_render.c -- off-screen frames, rut maps and PNG input/output
 * (DESIGN 6).  Every check reads decoded pixels, never PNG bytes.
 *
 * Set SS_TEST_KEEP=DIR to keep the images the tests write in DIR;
 * Frame times are reported as diagnostics, never asserted: speed is the
 * benchmark program's business (shared machines are noisy). */
#include "mesh.h"
#include "model_build.h"
#include "png_io.h"
#include "render.h"
#include "soilsim.h"
#include "tap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define SS_TEST_PI 3.14159265358979323846

static char outdir[512];

static const char *out_path(const char *name)
{
  static char buf[4][1024];
  static int k;
  k = (k + 1) % 4;
  snprintf(buf[k], sizeof buf[k], "%s/%s", outdir, name);
  return buf[k];
}

static double now_s(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* CPU time of the whole process (all of llvmpipe's threads included). */
static double cpu_s(void)
{
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const unsigned char *pix(const unsigned char *rgba, int w, int col, int row)
{
  return rgba + ((size_t)row * (size_t)w + (size_t)col) * 4;
}

/* max |difference| over the three channels */
static int rgb_diff(const unsigned char *p, int r, int g, int b)
{
  int d = abs(p[0] - r);
  if (abs(p[1] - g) > d) d = abs(p[1] - g);
  if (abs(p[2] - b) > d) d = abs(p[2] - b);
  return d;
}

/* ---------------------------------------------------------------------- */
/* a small world: a 2 m x 2 m soil bed, a blue box in its middle and an
 * imposed rectangular rut of depth RUT_DEPTH over x in [0.4, 0.8],
 * y in [-0.3, 0.3] */

#define BED_N 81 /* vertices per side: 2.5 cm spacing */
#define RUT_DEPTH 0.0082
#define RUT_X0 0.4
#define RUT_X1 0.8
#define RUT_Y0 -0.3
#define RUT_Y1 0.3

typedef struct world {
  ssModel *m;
  ssData *d;
  int bed, box;
} world;

static double bed_coord(int i) { return -1.0 + 2.0 * i / (BED_N - 1); }

static int in_rut(double x, double y)
{
  return x >= RUT_X0 - 1e-9 && x <= RUT_X1 + 1e-9 && y >= RUT_Y0 - 1e-9 &&
         y <= RUT_Y1 + 1e-9;
}

/* the world moved by X along x: the bed's centre and the box */
static int make_world_at(world *w, int with_box, double plastic_fraction, double X)
{
  ssError err;
  memset(w, 0, sizeof *w);
  w->m = ss_model_new();
  if (!w->m) return 0;
  double *z = calloc(BED_N * BED_N, sizeof *z);
  ssHfieldDef hd = ss_hfield_def_default();
  hd.name = "soil";
  hd.nx = hd.ny = BED_N;
  hd.x_size = hd.y_size = 2.0;
  hd.center_x = X;
  hd.height = z;
  hd.soil = 1;
  w->bed = ss_model_add_hfield(w->m, &hd, &err);
  free(z);
  if (w->bed < 0) {
    diag("add_hfield: %s", err.message);
    return 0;
  }
  w->box = -1;
  if (with_box) {
    ssBodyDef bd = ss_body_def_default();
    bd.name = "block";
    bd.shape = SS_GEOM_BOX;
    bd.size[0] = 0.3;
    bd.size[1] = 0.3;
    bd.size[2] = 0.1;
    bd.mass = 5;
    bd.pos[0] = X;
    bd.pos[2] = 0.05;
    bd.rgba[0] = 0.2;
    bd.rgba[1] = 0.4;
    bd.rgba[2] = 0.8;
    bd.rgba[3] = 1.0;
    w->box = ss_model_add_body(w->m, &bd, &err);
    if (w->box < 0) {
      diag("add_body: %s", err.message);
      return 0;
    }
  }
  w->d = ss_data_new(w->m);
  if (!w->d) return 0;
  ss_forward(w->m, w->d);

  double *s = calloc(BED_N * BED_N, sizeof *s), *p = calloc(BED_N * BED_N, sizeof *p);
  for (int j = 0; j < BED_N; j++)
    for (int i = 0; i < BED_N; i++)
      if (in_rut(bed_coord(i), bed_coord(j))) {
        s[j * BED_N + i] = RUT_DEPTH;
        p[j * BED_N + i] = plastic_fraction * RUT_DEPTH;
      }
  ssStatus st = ss_soil_set_state(w->m, w->d, w->bed, s, p, NULL, &err);
  free(s);
  free(p);
  if (st != SS_OK) {
    diag("soil_set_state: %s", err.message);
    return 0;
  }
  return 1;
}

static int make_world(world *w, int with_box, double plastic_fraction)
{
  return make_world_at(w, with_box, plastic_fraction, 0);
}

static void free_world(world *w)
{
  ss_data_free(w->d);
  ss_model_free(w->m);
  memset(w, 0, sizeof *w);
}

/* ---------------------------------------------------------------------- */

static void test_png_io(void)
{
  ssError err;
  int w = 37, h = 23;
  unsigned char *img = malloc((size_t)w * h * 4);
  for (int k = 0; k < w * h * 4; k++) img[k] = (unsigned char)(k * 7 + (k >> 5));
  const char *path = out_path("roundtrip.png");
  ok(ss_png_write_rgba(path, w, h, img, &err) == SS_OK, "png: write %dx%d", w, h);
  int w2 = 0, h2 = 0;
  unsigned char *back = NULL;
  ok(ss_png_read_rgba(path, &w2, &h2, &back, &err) == SS_OK && w2 == w && h2 == h &&
         memcmp(back, img, (size_t)w * h * 4) == 0,
     "png: RGBA round trip is exact");
  free(back);

  /* grey read of a grey-looking RGBA image */
  for (int k = 0; k < w * h; k++) {
    img[4 * k] = img[4 * k + 1] = img[4 * k + 2] = (unsigned char)(k % 256);
    img[4 * k + 3] = 255;
  }
  ss_png_write_rgba(path, w, h, img, &err);
  double *g = NULL;
  ok(ss_png_read_gray(path, &w2, &h2, &g, &err) == SS_OK && w2 == w && h2 == h,
     "png: grey read");
  if (g) {
    double worst = 0;
    for (int k = 0; k < w * h; k++)
      worst = fmax(worst, fabs(g[k] - (k % 256) / 255.0));
    ok(worst < 1e-12, "png: grey values of a grey image are v/255 (worst %.3g)", worst);
    free(g);
  }

  /* every truncation of a valid file is refused cleanly */
  FILE *f = fopen(path, "rb");
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  rewind(f);
  unsigned char *bytes = malloc((size_t)n);
  size_t got = fread(bytes, 1, (size_t)n, f);
  fclose(f);
  int accepted = 0, clean = 1;
  const char *tpath = out_path("truncated.png");
  for (long k = 0; k < (long)got; k += (k < 64 ? 1 : 7)) {
    FILE *o = fopen(tpath, "wb");
    fwrite(bytes, 1, (size_t)k, o);
    fclose(o);
    unsigned char *px = NULL;
    memset(&err, 0, sizeof err);
    ssStatus st = ss_png_read_rgba(tpath, &w2, &h2, &px, &err);
    if (st == SS_OK) {
      accepted++;
      free(px);
    } else if (px != NULL || strcmp(err.file, tpath) != 0 || !err.message[0]) {
      clean = 0;
    }
  }
  ok(accepted == 0 && clean, "png: truncated files are refused with the path and a message");
  memset(&err, 0, sizeof err);
  ss_png_read_rgba(tpath, &w2, &h2, &back, &err);
  diag("truncated: %s: %s", err.file, err.message);
  free(bytes);

  /* not a PNG at all */
  FILE *o = fopen(tpath, "wb");
  fputs("this is not an image\n", o);
  fclose(o);
  ok(ss_png_read_gray(tpath, &w2, &h2, &g, &err) == SS_ERR_PARSE &&
         strstr(err.message, "not a PNG") != NULL,
     "png: a text file is 'not a PNG file' (%s)", err.message);
  ok(ss_png_read_gray(out_path("missing.png"), &w2, &h2, &g, &err) == SS_ERR_IO,
     "png: a missing file is an I/O error");
  ok(ss_png_write_rgba("/nonexistent-dir/x/y.png", w, h, img, &err) == SS_ERR_IO &&
         strcmp(err.file, "/nonexistent-dir/x/y.png") == 0,
     "png: unwritable path fails cleanly (%s)", err.message);
  free(img);
}

static void test_colormap(void)
{
  unsigned char c[3];
  ss_colormap(0.0, c);
  ok(c[0] == SS_CMAP_ZERO_R && c[1] == SS_CMAP_ZERO_G && c[2] == SS_CMAP_ZERO_B,
     "colour map: t = 0 is the documented zero colour (%d %d %d)", c[0], c[1], c[2]);
  ss_colormap(1.0, c);
  ok(c[0] == SS_CMAP_DEEP_R && c[1] == SS_CMAP_DEEP_G && c[2] == SS_CMAP_DEEP_B,
     "colour map: t = 1 is the documented deep colour (%d %d %d)", c[0], c[1], c[2]);
  int invertible = 1, monotone = 1;
  double prev_l = 1e9;
  for (int k = 0; k < SS_CMAP_N; k++) {
    ss_colormap_entry(k, c);
    int d2;
    double t = ss_colormap_inverse(c, &d2);
    if (d2 != 0 || fabs(t - (double)k / (SS_CMAP_N - 1)) > 1e-12) invertible = 0;
    double l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    if (l > prev_l + 1e-9) monotone = 0;
    prev_l = l;
  }
  ok(invertible, "colour map: every entry reads back to its own value");
  ok(monotone, "colour map: lightness falls from zero to deep");
  close_enough(ss_nice_ceil(0.0082), 0.01, 1e-15, "full scale of 8.2 mm");
  close_enough(ss_nice_ceil(0.01), 0.01, 1e-15, "full scale of 10 mm");
  close_enough(ss_nice_ceil(0.0041), 0.005, 1e-15, "full scale of 4.1 mm");
  close_enough(ss_nice_ceil(0.021), 0.025, 1e-15, "full scale of 21 mm");
  close_enough(ss_nice_ceil(0.0), SS_FULL_SCALE_MIN, 0, "full scale of an untouched bed");
}

static void test_bad_sizes(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for size checks")) return;
  int sizes[][2] = {{0, 240}, {320, 0}, {100000, 240}, {320, 100000}, {-5, -5}};
  for (int k = 0; k < 5; k++) {
    ssRenderOptions o = ss_render_options_default();
    o.width = sizes[k][0];
    o.height = sizes[k][1];
    ssError err;
    memset(&err, 0, sizeof err);
    ssRenderer *r = ss_render_new(w.m, &o, &err);
    ok(r == NULL && err.code == SS_ERR_VALUE && strstr(err.message, "image size"),
       "render_new %d x %d fails: %s", o.width, o.height, err.message);
    ss_render_free(r);
  }
  ssRenderOptions o = ss_render_options_default();
  strcpy(o.camera_follow, "no_such_body");
  ssError err;
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  ok(r == NULL && err.code == SS_ERR_NOTFOUND,
     "render_new with an unknown follow target fails: %s", err.message);
  ss_render_free(r);
  /* a field of view outside (0, 180) degrees is refused, not drawn as 45 */
  double fovs[] = {0, -10, 180, 200, NAN};
  for (int k = 0; k < 5; k++) {
    o = ss_render_options_default();
    o.camera_fov_deg = fovs[k];
    memset(&err, 0, sizeof err);
    r = ss_render_new(w.m, &o, &err);
    ok(r == NULL && err.code == SS_ERR_VALUE && strstr(err.message, "field of view"),
       "render_new with a field of view of %g degrees fails: %s", fovs[k], err.message);
    ss_render_free(r);
  }
  free_world(&w);
}

/* The rut map's smallest sizes (soilsim.h) are the layout's: every width
 * from SS_RUT_MAP_MIN_WIDTH and height from SS_RUT_MAP_MIN_SIDE up lays
 * out a map inside the image, for beds long, square and wide (the CLI
 * refuses smaller sizes before the first step, so a size it accepts never
 * fails after the run); one pixel less either way is refused.  (The limit
 * said 64 a side while the layout needed 82 wide: --size 80x200 ran the
 * whole simulation, then failed.) */
static void test_rut_map_sizes(void)
{
  static const double beds[][2] = {{16, 6}, {2, 2}, {0.5, 40}, {40, 0.5}};
  long tried = 0, bad = 0;
  int first_bad_w = 0, first_bad_h = 0;
  for (int b = 0; b < 4; b++)
    for (int W = SS_RUT_MAP_MIN_WIDTH; W <= 2400; W += W < 600 ? 1 : 37)
      for (int H = SS_RUT_MAP_MIN_SIDE; H <= 2400; H += H < 600 ? 7 : 41) {
        ssRutMapLayout L;
        int laid = ss_rut_map_layout(W, H, beds[b][0], beds[b][1], &L);
        int inside = laid == 0 && L.map_w >= 1 && L.map_h >= 1 && L.map_x >= 0 &&
                     L.map_y >= 0 && L.bar_x + L.bar_w <= W && L.map_x + L.map_w <= W &&
                     L.map_y + L.map_h <= H && L.bar_y >= 0 && L.bar_y + L.bar_h <= H;
        tried++;
        if (!inside && !bad++) {
          first_bad_w = W;
          first_bad_h = H;
        }
      }
  ok(bad == 0, "rut map layout: %ld sizes from %dx%d up, 4 beds, all laid out inside "
     "the image (first failure %dx%d)", tried, SS_RUT_MAP_MIN_WIDTH, SS_RUT_MAP_MIN_SIDE,
     first_bad_w, first_bad_h);
  ssRutMapLayout L;
  ok(ss_rut_map_layout(SS_RUT_MAP_MIN_WIDTH - 1, 720, 16, 6, &L) != 0 &&
         ss_rut_map_layout(1280, SS_RUT_MAP_MIN_SIDE - 1, 16, 6, &L) != 0,
     "rut map layout: %dx720 and 1280x%d are refused", SS_RUT_MAP_MIN_WIDTH - 1,
     SS_RUT_MAP_MIN_SIDE - 1);
}

/* Camera straight down over the bed centre. */
static ssRenderOptions top_view(int W, int H)
{
  ssRenderOptions o = ss_render_options_default();
  o.width = W;
  o.height = H;
  o.camera_given = 1;
  o.camera_pos[0] = 0;
  o.camera_pos[1] = 0;
  o.camera_pos[2] = 4;
  o.camera_look_at[0] = 0;
  o.camera_look_at[1] = 0;
  o.camera_look_at[2] = 0;
  o.camera_fov_deg = 45;
  return o;
}

static void test_frame(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for frames")) return;
  int W = 320, H = 240;
  ssRenderOptions o = top_view(W, H);
  o.sinkage_max = RUT_DEPTH; /* the rut is exactly full scale */
  ssError err;
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  if (!ok(r != NULL, "render_new 320x240 (%s)", r ? "ok" : err.message)) {
    free_world(&w);
    return;
  }
  unsigned char *a = malloc((size_t)W * H * 4), *b = malloc((size_t)W * H * 4);
  ok(ss_render_pixels(r, w.m, w.d, a, &err) == SS_OK, "render_pixels");

  /* background corners */
  int corners[4][2] = {{0, 0}, {W - 1, 0}, {0, H - 1}, {W - 1, H - 1}};
  int bg = 1;
  for (int k = 0; k < 4; k++) {
    const unsigned char *p = pix(a, W, corners[k][0], corners[k][1]);
    if (p[0] != SS_CLEAR_R || p[1] != SS_CLEAR_G || p[2] != SS_CLEAR_B || p[3] != 255)
      bg = 0;
  }
  ok(bg, "frame corners show the clear colour (%d %d %d)", SS_CLEAR_R, SS_CLEAR_G,
     SS_CLEAR_B);

  /* the box's top faces the overhead light: exactly its own colour */
  double top[3] = {0, 0, 0.1}, col = -1, row = -1;
  int projected = ss_render_project(r, top, &col, &row);
  ok(projected && fabs(col - W / 2.0) < 1e-6 &&
         fabs(row - H / 2.0) < 1e-6,
     "the look-at point projects to the image centre (%.2f, %.2f)", col, row);
  const unsigned char *p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, 51, 102, 204) <= 1, "box top at its projected centre: %d %d %d, want 51 102 204",
     p[0], p[1], p[2]);

  /* the rut floor (full scale) and untouched soil */
  double rut[3] = {0.6, 0.0, -RUT_DEPTH}, soil[3] = {-0.6, 0.5, 0};
  ss_render_project(r, rut, &col, &row);
  p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, SS_CMAP_DEEP_R, SS_CMAP_DEEP_G, SS_CMAP_DEEP_B) <= 1,
     "rut floor pixel (%d, %d) has the deep colour: %d %d %d", (int)col, (int)row,
     p[0], p[1], p[2]);
  int rut_col = (int)col, rut_row = (int)row;
  ss_render_project(r, soil, &col, &row);
  p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) <= 1,
     "untouched soil pixel (%d, %d) has the zero colour: %d %d %d", (int)col,
     (int)row, p[0], p[1], p[2]);
  int soil_col = (int)col, soil_row = (int)row;

  /* image-up is world +y when looking straight down */
  double py[3] = {0, 0.5, 0}, px[3] = {0.5, 0, 0};
  double c1, r1, c2, r2;
  ss_render_project(r, py, &c1, &r1);
  ss_render_project(r, px, &c2, &r2);
  ok(r1 < H / 2.0 && fabs(c1 - W / 2.0) < 1e-6 && c2 > W / 2.0 && fabs(r2 - H / 2.0) < 1e-6,
     "top view: +y is up and +x is right in the image");

  /* the same state twice gives the same pixels */
  ok(ss_render_pixels(r, w.m, w.d, b, &err) == SS_OK &&
         memcmp(a, b, (size_t)W * H * 4) == 0,
     "rendering the same state twice gives identical pixels");

  /* the frame as a PNG decodes to the same pixels, at the requested size */
  const char *fp = out_path("frame_000000.png");
  ok(ss_render_frame(r, w.m, w.d, fp, &err) == SS_OK, "render_frame writes %s", fp);
  int w2 = 0, h2 = 0;
  unsigned char *back = NULL;
  ok(ss_png_read_rgba(fp, &w2, &h2, &back, &err) == SS_OK && w2 == W && h2 == H &&
         memcmp(back, a, (size_t)W * H * 4) == 0,
     "the PNG frame has the requested size %dx%d and the rendered pixels", W, H);
  free(back);
  memset(&err, 0, sizeof err);
  ok(ss_render_frame(r, w.m, w.d, "/nonexistent-dir/frame.png", &err) == SS_ERR_IO &&
         err.message[0],
     "unwritable frame path fails cleanly: %s: %s", err.file, err.message);
  ss_render_free(r);

  /* plain soil colour: the rut floor is lit like flat ground */
  o.color_mode = SS_COLOR_SOIL;
  r = ss_render_new(w.m, &o, &err);
  ss_render_pixels(r, w.m, w.d, b, &err);
  p = pix(b, W, rut_col, rut_row);
  ok(rgb_diff(p, SS_SOIL_R, SS_SOIL_G, SS_SOIL_B) <= 1,
     "soil colour mode: rut floor is the plain soil colour (%d %d %d)", p[0], p[1], p[2]);
  ss_render_free(r);

  /* permanent sinkage (half the rut) on an automatic scale of 5 mm */
  o.color_mode = SS_COLOR_PLASTIC;
  o.sinkage_max = 0;
  r = ss_render_new(w.m, &o, &err);
  ss_render_pixels(r, w.m, w.d, b, &err);
  p = pix(b, W, rut_col, rut_row);
  int d2;
  double v = ss_colormap_inverse(p, &d2) * ss_nice_ceil(0.5 * RUT_DEPTH);
  ok(fabs(v - 0.5 * RUT_DEPTH) <= ss_nice_ceil(0.5 * RUT_DEPTH) / (SS_CMAP_N - 1) && d2 <= 3,
     "plastic mode: rut floor decodes to %.3f mm (want %.3f)", v * 1e3,
     0.5 * RUT_DEPTH * 1e3);
  p = pix(b, W, soil_col, soil_row);
  ok(rgb_diff(p, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) <= 1,
     "plastic mode: untouched soil has the zero colour");
  ss_render_free(r);

  /* a removed body is not drawn: the soil under it shows */
  o.color_mode = SS_COLOR_SINKAGE;
  r = ss_render_new(w.m, &o, &err);
  ss_remove(w.m, w.d, "block", &err);
  ss_render_pixels(r, w.m, w.d, b, &err);
  p = pix(b, W, W / 2, H / 2);
  ok(rgb_diff(p, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) <= 1,
     "a removed body is not drawn (centre shows soil: %d %d %d)", p[0], p[1], p[2]);
  ss_render_free(r);

  free(a);
  free(b);
  free_world(&w);
}

/* Following a body keeps the camera's offset from it. */
/* The same world and camera moved 100 km along x give the same picture:
 * the bodies' and ground planes' vertices are sent to GL from the eye and
 * a bed's from its centre (render.c), so single precision holds them to
 * the scene's size.  From the world origin (before), the box drew ragged
 * and the bed over it in stripes.  A few pixels may part at edges where
 * a triangle's rasterised boundary falls on a pixel centre (at most
 * 0.5 % asked). */
static void test_far_from_origin(void)
{
  const int W = 240, H = 180;
  const double X = 1e5;
  unsigned char *img[2] = {malloc((size_t)W * H * 4), malloc((size_t)W * H * 4)};
  int good = img[0] && img[1];
  for (int k = 0; k < 2 && good; k++) {
    world w;
    good = make_world_at(&w, 1, 0.5, k ? X : 0);
    ssRenderOptions o = ss_render_options_default();
    o.width = W;
    o.height = H;
    o.camera_given = 1;
    double eye[3] = {-1.2, -1.6, 0.9}, at[3] = {0.1, 0.1, 0};
    for (int i = 0; i < 3; i++) {
      o.camera_pos[i] = eye[i] + (k && i == 0 ? X : 0);
      o.camera_look_at[i] = at[i] + (k && i == 0 ? X : 0);
    }
    o.sinkage_max = RUT_DEPTH;
    ssError err;
    ssRenderer *r = good ? ss_render_new(w.m, &o, &err) : NULL;
    good = r && ss_render_pixels(r, w.m, w.d, img[k], &err) == SS_OK;
    if (!good) diag("render: %s", err.message);
    ss_render_free(r);
    free_world(&w);
  }
  int differ = 0;
  for (int i = 0; good && i < W * H; i++)
    differ += memcmp(img[0] + 4 * i, img[1] + 4 * i, 4) != 0;
  ok(good && differ <= W * H / 200,
     "a scene 100 km from the origin renders as at the origin (%d of %d pixels differ, "
     "at most 0.5 %%)", differ, W * H);
  free(img[0]);
  free(img[1]);
}

static void test_follow(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for the follow camera")) return;
  int W = 200, H = 150;
  ssRenderOptions o = top_view(W, H);
  o.camera_pos[0] = 0.5; /* look at a point beside the box */
  o.camera_look_at[0] = 0.5;
  strcpy(o.camera_follow, "block");
  ssError err;
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  if (!ok(r != NULL, "render_new with camera_follow")) {
    free_world(&w);
    return;
  }
  unsigned char *a = malloc((size_t)W * H * 4);
  ss_render_pixels(r, w.m, w.d, a, &err);
  double top[3] = {0, 0, 0.1}, c0, r0, c1, r1;
  ss_render_project(r, top, &c0, &r0);
  /* move the box 0.3 m along -x and draw again */
  int q = w.m->sys_qadr[w.box];
  w.d->qpos[q] -= 0.3;
  ss_forward(w.m, w.d);
  ss_render_pixels(r, w.m, w.d, a, &err);
  double top1[3] = {-0.3, 0, 0.1};
  ss_render_project(r, top1, &c1, &r1);
  ok(fabs(c0 - c1) < 1e-6 && fabs(r0 - r1) < 1e-6,
     "a followed body stays at the same pixel (%.2f, %.2f) -> (%.2f, %.2f)", c0, r0, c1, r1);
  const unsigned char *p = pix(a, W, (int)c1, (int)r1);
  ok(rgb_diff(p, 51, 102, 204) <= 1, "and it is drawn there (%d %d %d)", p[0], p[1], p[2]);
  free(a);
  ss_render_free(r);
  free_world(&w);
}

/* A ground plane at the bed's height stays behind the bed; a rigid height
 * map is drawn in its plain colour. */
static void test_plane(void)
{
  world w;
  if (!ok(make_world(&w, 0, 0.5), "world for the ground plane")) return;
  ssError err;
  /* rebuild with a plane at z = 0 and a rigid map beside the bed */
  ss_data_free(w.d);
  ss_model_add_plane(w.m, "ground", 0.0, NULL, 0, &err);
  double z[4] = {0.2, 0.2, 0.2, 0.2};
  ssHfieldDef hd = ss_hfield_def_default();
  hd.name = "rock";
  hd.x_size = hd.y_size = 0.5;
  hd.height = z;
  hd.pos[0] = -1.5;
  int rock = ss_model_add_hfield(w.m, &hd, &err);
  w.d = ss_data_new(w.m);
  ok(rock == 1 && w.d != NULL, "plane and rigid height map added");
  int W = 320, H = 240;
  ssRenderOptions o = top_view(W, H);
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  unsigned char *a = malloc((size_t)W * H * 4);
  ok(r && ss_render_pixels(r, w.m, w.d, a, &err) == SS_OK, "frame with a ground plane");
  double soil[3] = {-0.6, 0.5, 0}, rk[3] = {-1.5, 0, 0.2}, col, row;
  ss_render_project(r, soil, &col, &row);
  const unsigned char *p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) <= 1,
     "a plane at the bed's height stays behind it (%d %d %d)", p[0], p[1], p[2]);
  p = pix(a, W, 0, H - 1);
  ok(rgb_diff(p, SS_PLANE_R, SS_PLANE_G, SS_PLANE_B) <= 1,
     "the ground plane fills the corner in its grey (%d %d %d)", p[0], p[1], p[2]);
  ss_render_project(r, rk, &col, &row);
  p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, SS_RIGID_R, SS_RIGID_G, SS_RIGID_B) <= 1,
     "a rigid height map is drawn in its plain grey (%d %d %d)", p[0], p[1], p[2]);
  free(a);
  ss_render_free(r);
  free_world(&w);
}

/* The automatic overview frames the first soil bed. */
static void test_auto_camera(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for the automatic camera")) return;
  int W = 320, H = 180;
  ssRenderOptions o = ss_render_options_default();
  o.width = W;
  o.height = H;
  ssError err;
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  unsigned char *a = malloc((size_t)W * H * 4);
  ok(r && ss_render_pixels(r, w.m, w.d, a, &err) == SS_OK, "automatic camera frame");
  int inside = 1;
  for (int k = 0; k < 4; k++) {
    double c[3] = {(k & 1) ? 1 : -1, (k & 2) ? 1 : -1, 0}, col, row;
    if (!ss_render_project(r, c, &col, &row) || col < 0 || col > W || row < 0 || row > H)
      inside = 0;
  }
  ok(inside, "all four bed corners are inside the automatic view");
  const unsigned char *p = pix(a, W, 0, 0);
  ok(p[0] == SS_CLEAR_R && p[1] == SS_CLEAR_G && p[2] == SS_CLEAR_B,
     "automatic view: corner shows the sky");
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, w.m, w.d, out_path("auto.png"), &err);
  free(a);
  ss_render_free(r);
  free_world(&w);
}

/* ---------------------------------------------------------------------- */
/* visual meshes and collision-only geoms                                  */

/* Axis-aligned box [-hx, hx] x [-hy, hy] x [-hz, hz] as a triangle mesh,
 * wound counter-clockwise seen from outside (8 shared corners: the
 * renderer must not smooth across its edges). */
static ssMesh *box_mesh(double hx, double hy, double hz)
{
  double v[24];
  for (int k = 0; k < 8; k++) {
    v[3 * k] = (k & 1) ? hx : -hx;
    v[3 * k + 1] = (k & 2) ? hy : -hy;
    v[3 * k + 2] = (k & 4) ? hz : -hz;
  }
  static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  int t[36];
  for (int q = 0; q < 6; q++) {
    const int *c = quads[q];
    int tri[6] = {c[0], c[1], c[2], c[0], c[2], c[3]};
    memcpy(t + 6 * q, tri, sizeof tri);
  }
  ssMesh *me = NULL;
  ssError err;
  if (ss_mesh_from_arrays(v, 8, t, 12, &me, &err) != SS_OK) diag("mesh: %s", err.message);
  return me;
}

/* A flat 2 m soil bed; body "carrier" (a blue 0.3 x 0.3 x 0.1 box collider,
 * collision-only, yawed 90 degrees, at x = -0.5) carrying a red mesh visual
 * (a 0.2 x 0.2 x 0.04 box 5 cm ahead of its centre and 7 cm up); body
 * "bare" (a green box at x = +0.5 whose only geom is a collider). */
typedef struct meshWorld {
  ssModel *m;
  ssData *d;
  int carrier, bare;     /* bodies */
  int collider, visual;  /* the carrier's geoms */
} meshWorld;

static int make_mesh_world(meshWorld *w)
{
  ssError err;
  memset(w, 0, sizeof *w);
  w->m = ss_model_new();
  double *z = calloc(BED_N * BED_N, sizeof *z);
  ssHfieldDef hd = ss_hfield_def_default();
  hd.name = "soil";
  hd.nx = hd.ny = BED_N;
  hd.x_size = hd.y_size = 2.0;
  hd.height = z;
  hd.soil = 1;
  int bed = ss_model_add_hfield(w->m, &hd, &err);
  free(z);
  if (bed < 0) return 0;

  ssBodyDef bd = ss_body_def_default();
  bd.name = "carrier";
  bd.shape = SS_GEOM_BOX;
  bd.size[0] = bd.size[1] = 0.3;
  bd.size[2] = 0.1;
  bd.mass = 5;
  bd.pos[0] = -0.5;
  bd.pos[2] = 0.05;
  bd.quat[0] = cos(SS_TEST_PI / 4);
  bd.quat[3] = sin(SS_TEST_PI / 4);
  bd.rgba[0] = 0.2;
  bd.rgba[1] = 0.4;
  bd.rgba[2] = 0.8;
  bd.rgba[3] = 1;
  int s1 = ss_model_add_body(w->m, &bd, &err);
  bd.name = "bare";
  bd.pos[0] = 0.5;
  bd.quat[0] = 1;
  bd.quat[3] = 0;
  bd.rgba[0] = 0.2;
  bd.rgba[1] = 0.8;
  bd.rgba[2] = 0.4;
  int s2 = ss_model_add_body(w->m, &bd, &err);
  if (s1 < 0 || s2 < 0) {
    diag("add_body: %s", err.message);
    return 0;
  }
  w->carrier = w->m->sys_bodyadr[s1];
  w->bare = w->m->sys_bodyadr[s2];
  w->collider = -1;
  for (int g = 0; g < w->m->ngeom; g++) {
    /* single bodies' geoms collide and are drawn (group 3); make both
     * collision-only */
    if (w->m->geom_body[g] == w->carrier) w->collider = g;
    w->m->geom_group[g] = 1;
  }
  ssMesh *me = box_mesh(0.1, 0.1, 0.02);
  int k = me ? ss_model_push_mesh(w->m, me, "box_mesh", &err) : -1;
  if (k < 0) {
    ss_mesh_free(me);
    return 0;
  }
  double size[3] = {0.2, 0.2, 0.04}, pos[3] = {0.05, 0, 0.07}, quat[4] = {1, 0, 0, 0};
  double red[4] = {0.8, 0.2, 0.2, 1};
  w->visual = ss_model_push_geom(w->m, w->carrier, SS_GEOM_MESH, size, pos, quat, 0, red,
                                 2, k, &err);
  if (w->visual < 0 || w->collider < 0) return 0;
  w->d = ss_data_new(w->m);
  if (!w->d) return 0;
  ss_forward(w->m, w->d);
  return 1;
}

/* World point of a point given in geom g's frame. */
static void geom_point(const ssData *d, int g, const double local[3], double out[3])
{
  const double *R = d->geom_xmat + 9 * g, *p = d->geom_xpos + 3 * g;
  for (int i = 0; i < 3; i++)
    out[i] = p[i] + R[3 * i] * local[0] + R[3 * i + 1] * local[1] + R[3 * i + 2] * local[2];
}

static void test_mesh_visuals(void)
{
  meshWorld w;
  if (!ok(make_mesh_world(&w), "world with a mesh visual and collision-only geoms")) {
    ss_data_free(w.d);
    ss_model_free(w.m);
    return;
  }
  int W = 320, H = 240;
  ssRenderOptions o = top_view(W, H);
  ssError err;
  ssRenderer *r = ss_render_new(w.m, &o, &err);
  unsigned char *a = malloc((size_t)W * H * 4), *b = malloc((size_t)W * H * 4);
  if (!ok(r && ss_render_pixels(r, w.m, w.d, a, &err) == SS_OK, "frame with a mesh visual")) {
    ss_render_free(r);
    free(a);
    free(b);
    ss_data_free(w.d);
    ss_model_free(w.m);
    return;
  }
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, w.m, w.d, out_path("mesh_visual.png"), &err);

  /* the mesh's top face at its projected centre: exactly its colour */
  double ltop[3] = {0, 0, 0.02}, top[3], col, row;
  geom_point(w.d, w.visual, ltop, top);
  ok(fabs(top[0] + 0.5) < 1e-9 && fabs(top[1] - 0.05) < 1e-9 && fabs(top[2] - 0.14) < 1e-9,
     "the visual's pose follows the body's (%.3f %.3f %.3f)", top[0], top[1], top[2]);
  ss_render_project(r, top, &col, &row);
  const unsigned char *p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, 204, 51, 51) <= 1,
     "mesh visual at its projected centre has its colour: %d %d %d, want 204 51 51", p[0],
     p[1], p[2]);
  /* near the mesh's corner: flat shading across the box's shared corners */
  double lcorner[3] = {0.07, 0.07, 0.02}, corner[3];
  geom_point(w.d, w.visual, lcorner, corner);
  ss_render_project(r, corner, &col, &row);
  p = pix(a, W, (int)floor(col), (int)floor(row));
  ok(rgb_diff(p, 204, 51, 51) <= 1,
     "a mesh box's top is flat-shaded up to its corner: %d %d %d", p[0], p[1], p[2]);

  /* on the carrier's collider but off the visual: soil shows */
  double lhid[3] = {-0.12, 0.0, 0.05}, hid[3];
  geom_point(w.d, w.collider, lhid, hid);
  ss_render_project(r, hid, &col, &row);
  int hid_col = (int)col, hid_row = (int)row;
  p = pix(a, W, hid_col, hid_row);
  ok(rgb_diff(p, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) <= 1,
     "a collision-only geom of a body with a visual is hidden (soil: %d %d %d)", p[0], p[1],
     p[2]);

  /* a body with no visual geom shows its collider */
  double bare_top[3] = {0.5, 0, 0.1};
  ss_render_project(r, bare_top, &col, &row);
  p = pix(a, W, (int)col, (int)row);
  ok(rgb_diff(p, 51, 204, 102) <= 1,
     "a body without visuals shows its collider: %d %d %d, want 51 204 102", p[0], p[1],
     p[2]);

  /* take the visual away: the carrier falls back to its collider */
  w.m->geom_group[w.visual] = 0;
  ok(ss_render_pixels(r, w.m, w.d, b, &err) == SS_OK, "frame without the visual");
  p = pix(b, W, hid_col, hid_row);
  ok(rgb_diff(p, 51, 102, 204) <= 1,
     "without visual geoms the body's collider is drawn: %d %d %d, want 51 102 204", p[0],
     p[1], p[2]);
  ss_render_project(r, top, &col, &row);
  p = pix(b, W, (int)col, (int)row);
  ok(rgb_diff(p, 204, 51, 51) > 20, "and the hidden visual is gone (%d %d %d)", p[0], p[1],
     p[2]);
  w.m->geom_group[w.visual] = 2;
  ok(ss_render_pixels(r, w.m, w.d, b, &err) == SS_OK &&
         memcmp(a, b, (size_t)W * H * 4) == 0,
     "visual back: the first frame again, pixel for pixel");
  ss_render_free(r);
  free(a);
  free(b);
  ss_data_free(w.d);
  ss_model_free(w.m);
}

static int find_body(const ssModel *m, const char *name)
{
  for (int b = 0; b < m->nbody; b++)
    if (m->body_name[b] && strcmp(m->body_name[b], name) == 0) return b;
  return -1;
}

static int find_geom(const ssModel *m, int body, int type)
{
  for (int g = 0; g < m->ngeom; g++)
    if (m->geom_body[g] == body && m->geom_type[g] == type) return g;
  return -1;
}

/* A camera at eye looking at target, W x H. */
static ssRenderOptions look(int W, int H, const double eye[3], const double target[3],
                            double fov)
{
  ssRenderOptions o = ss_render_options_default();
  o.width = W;
  o.height = H;
  o.camera_given = 1;
  memcpy(o.camera_pos, eye, sizeof o.camera_pos);
  memcpy(o.camera_look_at, target, sizeof o.camera_look_at);
  o.camera_fov_deg = fov;
  return o;
}

/* The buggy of scenes/buggy.xml: links drawn from their OBJ visuals, the
 * wheels' collider cylinders hidden. */
static void test_buggy_visuals(void)
{
  const char *top = getenv("top_srcdir");
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/buggy.xml", top && *top ? top : ".");
  if (access(path, R_OK) != 0) {
    ok(1, "buggy visuals # SKIP %s not found (set top_srcdir)", path);
    return;
  }
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError err;
  ss_error_clear(&err);
  ssStatus st = ss_scene_load(path, &m, &d, &err);
  if (!ok(st == SS_OK, "buggy scene loads%s%s", st ? ": " : "", st ? err.message : ""))
    return;
  ss_forward(m, d);
  int chassis = find_body(m, "chassis"), wheel = find_body(m, "wheel_fl");
  int gch = find_geom(m, chassis, SS_GEOM_MESH), gwm = find_geom(m, wheel, SS_GEOM_MESH);
  int gwc = find_geom(m, wheel, SS_GEOM_CYLINDER);
  if (!ok(gch >= 0 && gwm >= 0 && gwc >= 0 && (m->geom_group[gwc] & 2) == 0 &&
              (m->geom_group[gwm] & 2) != 0,
          "buggy: chassis mesh, wheel mesh visual and collision-only wheel cylinder")) {
    ss_data_free(d);
    ss_model_free(m);
    return;
  }
  int W = 320, H = 240;
  unsigned char *a = malloc((size_t)W * H * 4);

  /* straight down onto the engine block's flat top (chassis frame
   * (-0.85, 0, 0.42)): the chassis colour exactly */
  double leng[3] = {-0.85, 0, 0.42}, eng[3], eye[3];
  geom_point(d, gch, leng, eng);
  memcpy(eye, eng, sizeof eye);
  eye[2] += 3;
  ssRenderOptions o = look(W, H, eye, eng, 10);
  ssRenderer *r = ss_render_new(m, &o, &err);
  ok(r && ss_render_pixels(r, m, d, a, &err) == SS_OK, "buggy: top view renders");
  const double *c = m->geom_rgba + 4 * gch;
  int want[3] = {(int)floor(c[0] * 255 + 0.5), (int)floor(c[1] * 255 + 0.5),
                 (int)floor(c[2] * 255 + 0.5)};
  const unsigned char *p = pix(a, W, W / 2, H / 2);
  ok(rgb_diff(p, want[0], want[1], want[2]) <= 1,
     "buggy: the chassis mesh shows its colour at the engine top: %d %d %d, want %d %d %d",
     p[0], p[1], p[2], want[0], want[1], want[2]);
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, m, d, out_path("buggy_top.png"), &err);
  ss_render_free(r);

  /* from the left, onto the front-left wheel's recessed disc 12 cm from
   * its axle: the collider's flat cap would cover it in its own colour */
  double lw[3] = {0.12, 0, 0}, wp[3];
  geom_point(d, gwm, lw, wp);
  memcpy(eye, wp, sizeof eye);
  eye[1] += 2.5;
  o = look(W, H, eye, wp, 10);
  r = ss_render_new(m, &o, &err);
  ok(r && ss_render_pixels(r, m, d, a, &err) == SS_OK, "buggy: side view renders");
  p = pix(a, W, W / 2, H / 2);
  const double *cc = m->geom_rgba + 4 * gwc;
  int grey = abs(p[0] - p[2]) <= 3 && abs(p[0] - p[1]) <= 3 && p[0] < 80;
  ok(grey, "buggy: the wheel shows its grey mesh, not the %.2f %.2f %.2f collider cap "
           "(%d %d %d)", cc[0], cc[1], cc[2], p[0], p[1], p[2]);
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, m, d, out_path("buggy_wheel.png"), &err);
  ss_render_free(r);
  free(a);
  ss_data_free(d);
  ss_model_free(m);
}

/* ---------------------------------------------------------------------- */
/* GL backends: SOILSIM_GL chooses; EGL gives the pixels OSMesa gives      */

static void set_gl_env(const char *v)
{
  if (v) setenv(SS_GL_ENV, v, 1);
  else unsetenv(SS_GL_ENV);
}

/* The test world's top view through the backend named (NULL: default). */
static ssRenderer *frame_with(const world *w, const char *backend, int W, int H,
                              unsigned char *rgba, ssError *err)
{
  set_gl_env(backend);
  ssRenderOptions o = top_view(W, H);
  o.sinkage_max = RUT_DEPTH;
  ssRenderer *r = ss_render_new(w->m, &o, err);
  if (r && ss_render_pixels(r, w->m, w->d, rgba, err) != SS_OK) {
    ss_render_free(r);
    r = NULL;
  }
  return r;
}

static void test_gl_backends(void)
{
  const char *saved = getenv(SS_GL_ENV);
  char keep[64] = "";
  if (saved) snprintf(keep, sizeof keep, "%s", saved);
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for the GL backends")) return;
  int W = 200, H = 150;
  unsigned char *a = malloc((size_t)W * H * 4), *b = malloc((size_t)W * H * 4);
  unsigned char *c = malloc((size_t)W * H * 4);
  ssError err;

  diag("GL backends built: osmesa %d, egl %d; configure default %s",
       ss_glctx_backend_built("osmesa"), ss_glctx_backend_built("egl"),
       ss_glctx_default_backend());
  ok(ss_glctx_backend_built("osmesa") && !ss_glctx_backend_built("vulkan"),
     "OSMesa is built; unknown backends are not");

  memset(&err, 0, sizeof err);
  ssRenderer *r = frame_with(&w, "bogus", W, H, a, &err);
  ok(r == NULL && err.code == SS_ERR_VALUE && strstr(err.message, SS_GL_ENV) &&
         strstr(err.message, "osmesa or egl"),
     "SOILSIM_GL=bogus is refused: %s", err.message);
  ss_render_free(r);

  r = frame_with(&w, "osmesa", W, H, a, &err);
  ok(r && strcmp(ss_render_backend_name(r), "OSMesa") == 0,
     "SOILSIM_GL=osmesa renders with OSMesa (%s)", r ? ss_render_backend_name(r) : err.message);
  ss_render_free(r);

  if (!ss_glctx_backend_built("egl")) {
    memset(&err, 0, sizeof err);
    r = frame_with(&w, "egl", W, H, b, &err);
    ok(r == NULL && err.code == SS_ERR_UNSUPPORTED,
       "SOILSIM_GL=egl without an EGL build fails clearly: %s", err.message);
    ss_render_free(r);
    ok(1, "EGL backend # SKIP not built (configure found no libegl-dev)");
  } else {
    memset(&err, 0, sizeof err);
    ssRenderer *re = frame_with(&w, "egl", W, H, b, &err);
    if (!re) {
      ok(1, "EGL backend # SKIP cannot start here: %s", err.message);
    } else {
      ok(strcmp(ss_render_backend_name(re), "EGL") == 0, "SOILSIM_GL=egl renders with EGL");
      long differ = 0;
      int worst = 0;
      for (long k = 0; k < (long)W * H; k++) {
        int d = rgb_diff(a + 4 * k, b[4 * k], b[4 * k + 1], b[4 * k + 2]);
        if (d) differ++;
        if (d > worst) worst = d;
      }
      ok(worst <= 1, "EGL and OSMesa frames agree (%ld pixels differ, by at most %d)", differ,
         worst);
      const unsigned char *p = pix(b, W, 0, 0);
      ok(p[0] == SS_CLEAR_R && p[1] == SS_CLEAR_G && p[2] == SS_CLEAR_B && p[3] == 255,
         "EGL: the corner has the clear colour");
      /* both kinds of context alive in one process, drawing in turn */
      set_gl_env("osmesa");
      ssRenderOptions o = top_view(W, H);
      o.sinkage_max = RUT_DEPTH;
      ssRenderer *ro = ss_render_new(w.m, &o, &err);
      int same = ro != NULL;
      for (int k = 0; k < 2 && same; k++) {
        same = ss_render_pixels(ro, w.m, w.d, c, &err) == SS_OK &&
               memcmp(c, a, (size_t)W * H * 4) == 0;
        same = same && ss_render_pixels(re, w.m, w.d, c, &err) == SS_OK &&
               memcmp(c, b, (size_t)W * H * 4) == 0;
      }
      ok(same, "an OSMesa and an EGL renderer drawing in turn each keep their pixels");
      ss_render_free(ro);
      ss_render_free(re);
      /* and EGL starts again after its last context went */
      re = frame_with(&w, "egl", W, H, c, &err);
      ok(re && memcmp(c, b, (size_t)W * H * 4) == 0,
         "EGL starts again after its last context was freed");
      ss_render_free(re);
    }
  }
  set_gl_env(saved ? keep : NULL);
  free(a);
  free(b);
  free(c);
  free_world(&w);
}

/* the rut map of the plate scene itself (scenes/plate.xml simulated until
 * the plate has settled): footprint pixels read the analytic 8.175 mm
 * within the colour bar's resolution, pixels away from it read zero */
static void test_plate_scene_rut_map(void)
{
  const char *top = getenv("top_srcdir");
  char scene[1024];
  snprintf(scene, sizeof scene, "%s/scenes/plate.xml", top && *top ? top : ".");
  ssModel *m;
  ssData *d;
  ssError err;
  ss_error_clear(&err);
  ssStatus st = ss_scene_load(scene, &m, &d, &err);
  if (!ok(st == SS_OK, "plate scene loads%s%s", st ? ": " : "", st ? err.message : ""))
    return;
  int steps_ok = 1;
  for (int k = 0; k < 1500 && steps_ok; k++) steps_ok = ss_step(m, d, &err) == SS_OK;
  int W = 480, H = 400;
  const char *path = out_path("plate_ruts.png");
  unsigned char *a = NULL;
  int w2 = 0, h2 = 0;
  if (!ok(steps_ok && ss_render_rut_map(m, d, -1, 0, W, H, path, &err) == SS_OK &&
              ss_png_read_rgba(path, &w2, &h2, &a, &err) == SS_OK && w2 == W && h2 == H,
          "plate scene: settled, rut map written and decoded at %dx%d", W, H)) {
    free(a);
    ss_data_free(d);
    ss_model_free(m);
    return;
  }
  double xs = m->hfield_size[0], ys = m->hfield_size[1];
  int n = m->hfield_nx[0];
  double h = xs / (n - 1), s_ref = 8.175e-3;
  ssRutMapLayout L;
  ss_rut_map_layout(W, H, xs, ys, &L);
  double fs = ss_nice_ceil(s_ref), res = fs / (SS_CMAP_N - 1);
  long n_in = 0, bad_in = 0, n_out = 0, bad_out = 0;
  for (int row = L.map_y; row < L.map_y + L.map_h; row++)
    for (int col = L.map_x; col < L.map_x + L.map_w; col++) {
      double u = (col - L.map_x + 0.5) / L.map_w, v = 1 - (row - L.map_y + 0.5) / L.map_h;
      double x = -xs / 2 + xs * u, y = -ys / 2 + ys * v;
      const unsigned char *p = pix(a, W, col, row);
      if (fabs(x) < 0.2 - h && fabs(y) < 0.3 - h) {
        int d2;
        double val = ss_colormap_inverse(p, &d2) * fs;
        n_in++;
        if (fabs(val - s_ref) > res) bad_in++;
      } else if (fabs(x) > 0.2 + h || fabs(y) > 0.3 + h) {
        n_out++;
        if (p[0] != SS_CMAP_ZERO_R || p[1] != SS_CMAP_ZERO_G || p[2] != SS_CMAP_ZERO_B)
          bad_out++;
      }
    }
  ok(n_in > 1000 && bad_in == 0,
     "plate scene rut map: %ld footprint pixels read 8.175 mm within %.3f mm (%ld off)",
     n_in, res * 1e3, bad_in);
  ok(n_out > 10000 && bad_out == 0, "plate scene rut map: %ld pixels off the plate read zero (%ld off)",
     n_out, bad_out);
  free(a);
  ss_data_free(d);
  ss_model_free(m);
}

/* A narrow rut map: the title stops short of the colour bar's labels (a
 * long one ran over the top label "10 mm" at 320 x 180), shortened as
 * needed, and still says what the map shows. */
static void test_rut_map_title(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for a narrow rut map")) return;
  int W = 320, H = 180;
  ssError err;
  const char *path = out_path("ruts_narrow.png");
  int w2 = 0, h2 = 0;
  unsigned char *a = NULL;
  ssRutMapLayout L;
  if (!ok(ss_render_rut_map(w.m, w.d, -1, 1, W, H, path, &err) == SS_OK &&
              ss_png_read_rgba(path, &w2, &h2, &a, &err) == SS_OK && w2 == W &&
              h2 == H && ss_rut_map_layout(W, H, 2.0, 2.0, &L) == 0,
          "narrow rut map written and decoded")) {
    free(a);
    free_world(&w);
    return;
  }
  /* the rows above the top label's glyphs, right of where the labels
   * begin: only paper there */
  int label_x = L.bar_x + L.bar_w + 7 - L.font_px / 2, ink = 0, title = 0;
  for (int row = 0; row < L.bar_y - L.font_px; row++)
    for (int col = 0; col < W; col++) {
      const unsigned char *p = pix(a, W, col, row);
      int paper = p[0] == SS_PAPER_R && p[1] == SS_PAPER_G && p[2] == SS_PAPER_B;
      if (!paper && col >= label_x) ink++;
      if (!paper && col < label_x) title++;
    }
  ok(title > 0 && ink == 0,
     "narrow rut map: the title (%d pixels) ends before the colour bar's labels "
     "(%d pixels beyond)", title, ink);
  free(a);
  unlink(path);
  free_world(&w);
}

static void test_rut_map(void)
{
  world w;
  if (!ok(make_world(&w, 1, 0.5), "world for rut maps")) return;
  int W = 640, H = 400;
  ssError err;
  const char *path = out_path("ruts.png");
  ok(ss_render_rut_map(w.m, w.d, -1, 0, W, H, path, &err) == SS_OK,
     "rut map of total sinkage written");
  int w2 = 0, h2 = 0;
  unsigned char *a = NULL;
  if (!ok(ss_png_read_rgba(path, &w2, &h2, &a, &err) == SS_OK && w2 == W && h2 == H,
          "rut map decodes at the requested size %dx%d", W, H)) {
    free(a);
    free_world(&w);
    return;
  }
  ssRutMapLayout L;
  int laid = ss_rut_map_layout(W, H, 2.0, 2.0, &L);
  ok(laid == 0 && L.map_w > 100 &&
         abs(L.map_w - L.map_h) <= 1,
     "layout: a square bed gets a square map (%d x %d at %d, %d)", L.map_w, L.map_h,
     L.map_x, L.map_y);

  /* every map pixel: inside the rut (a cell away from its edge) it reads
   * 8.2 mm; a cell away from the rut it is exactly the zero colour */
  double fs = ss_nice_ceil(RUT_DEPTH), res = fs / (SS_CMAP_N - 1);
  double cell = 2.0 / (BED_N - 1);
  long n_in = 0, bad_in = 0, n_out = 0, bad_out = 0;
  double worst = 0;
  for (int row = L.map_y; row < L.map_y + L.map_h; row++)
    for (int col = L.map_x; col < L.map_x + L.map_w; col++) {
      double u = (col - L.map_x + 0.5) / L.map_w, v = 1 - (row - L.map_y + 0.5) / L.map_h;
      double x = -1 + 2 * u, y = -1 + 2 * v;
      const unsigned char *p = pix(a, W, col, row);
      int inner = x > RUT_X0 + cell && x < RUT_X1 - cell && y > RUT_Y0 + cell &&
                  y < RUT_Y1 - cell;
      int outer = x < RUT_X0 - cell || x > RUT_X1 + cell || y < RUT_Y0 - cell ||
                  y > RUT_Y1 + cell;
      if (inner) {
        int d2;
        double val = ss_colormap_inverse(p, &d2) * fs;
        worst = fmax(worst, fabs(val - RUT_DEPTH));
        n_in++;
        if (fabs(val - RUT_DEPTH) > res || d2 != 0) bad_in++;
      } else if (outer) {
        n_out++;
        if (p[0] != SS_CMAP_ZERO_R || p[1] != SS_CMAP_ZERO_G || p[2] != SS_CMAP_ZERO_B)
          bad_out++;
      }
    }
  ok(n_in > 1000 && bad_in == 0,
     "rut map: %ld footprint pixels read 8.2 mm within %.3f mm (worst %.4f mm, %ld off)",
     n_in, res * 1e3, worst * 1e3, bad_in);
  ok(n_out > 10000 && bad_out == 0,
     "rut map: %ld pixels off the rut have exactly the zero colour (%ld off)", n_out,
     bad_out);

  /* the pixel of one bed point, through the layout */
  int col, row;
  ss_rut_map_pixel(&L, (0.6 + 1) / 2, (0.0 + 1) / 2, &col, &row);
  int d2;
  double val = ss_colormap_inverse(pix(a, W, col, row), &d2) * fs;
  close_enough(val * 1e3, RUT_DEPTH * 1e3, res * 1e3, "rut centre (0.6, 0) in mm");

  /* colour bar: full scale at the top, zero at the bottom */
  const unsigned char *t = pix(a, W, L.bar_x + L.bar_w / 2, L.bar_y);
  const unsigned char *bt = pix(a, W, L.bar_x + L.bar_w / 2, L.bar_y + L.bar_h - 1);
  ok(rgb_diff(t, SS_CMAP_DEEP_R, SS_CMAP_DEEP_G, SS_CMAP_DEEP_B) == 0 &&
         rgb_diff(bt, SS_CMAP_ZERO_R, SS_CMAP_ZERO_G, SS_CMAP_ZERO_B) == 0,
     "colour bar: deep colour on top, zero colour at the bottom");
  /* labels and the scale bar are drawn in ink somewhere right of the bar
   * and under the map */
  long ink_right = 0, ink_below = 0;
  for (int r2 = 0; r2 < H; r2++)
    for (int c2 = L.bar_x + L.bar_w + 2; c2 < W; c2++)
      if (pix(a, W, c2, r2)[0] < 100) ink_right++;
  for (int r2 = L.map_y + L.map_h + 2; r2 < H; r2++)
    for (int c2 = 0; c2 < W; c2++)
      if (pix(a, W, c2, r2)[0] < 100) ink_below++;
  ok(ink_right > 50 && ink_below > 50, "labels beside the bar (%ld px) and a scale below (%ld px)",
     ink_right, ink_below);
  ok(L.scale_len > 0 && fabs(L.scale_len - L.scale_m / 2.0 * L.map_w) <= 0.5,
     "metre scale: %g m is %d px on a %d px wide 2 m map", L.scale_m, L.scale_len, L.map_w);
  const unsigned char *corner = pix(a, W, 0, H - 1);
  ok(corner[0] == 255 && corner[1] == 255 && corner[2] == 255, "rut map paper is white");
  free(a);

  /* permanent sinkage: 4.1 mm on a 5 mm scale */
  path = out_path("ruts_plastic.png");
  ok(ss_render_rut_map(w.m, w.d, 0, 1, W, H, path, &err) == SS_OK,
     "rut map of permanent sinkage written");
  ss_png_read_rgba(path, &w2, &h2, &a, &err);
  fs = ss_nice_ceil(0.5 * RUT_DEPTH);
  val = ss_colormap_inverse(pix(a, W, col, row), &d2) * fs;
  close_enough(val * 1e3, 0.5 * RUT_DEPTH * 1e3, fs / (SS_CMAP_N - 1) * 1e3,
               "permanent rut centre in mm");
  free(a);

  /* rut map errors */
  ok(ss_render_rut_map(w.m, w.d, -1, 0, 10, 10, out_path("tiny.png"), &err) == SS_ERR_VALUE,
     "rut map 10x10 is refused: %s", err.message);
  ok(ss_render_rut_map(w.m, w.d, 5, 0, W, H, out_path("x.png"), &err) == SS_ERR_VALUE,
     "rut map of a missing height map is refused: %s", err.message);
  ok(ss_render_rut_map(w.m, w.d, -1, 0, W, H, "/nonexistent-dir/ruts.png", &err) == SS_ERR_IO,
     "unwritable rut map path fails cleanly: %s", err.message);
  free_world(&w);

  ssModel *m = ss_model_new();
  ssData *d = ss_data_new(m);
  ok(ss_render_rut_map(m, d, -1, 0, W, H, out_path("none.png"), &err) == SS_ERR_NOTFOUND,
     "rut map of a world without soil: %s", err.message);
  ss_data_free(d);
  ss_model_free(m);
}

/* The size of the vehicle scene: a 16 m x 6 m bed of 801 x 301 vertices
 * with two ruts, a ground plane and 40 primitives, at 1280 x 720. */
static void test_timing(void)
{
  ssError err;
  ssModel *m = ss_model_new();
  int nx = 801, ny = 301;
  double *z = malloc(sizeof *z * (size_t)nx * ny);
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++)
      z[j * nx + i] = 0.03 * sin(0.05 * i) * cos(0.07 * j);
  ssHfieldDef hd = ss_hfield_def_default();
  hd.name = "bed";
  hd.nx = nx;
  hd.ny = ny;
  hd.x_size = 16;
  hd.y_size = 6;
  hd.height = z;
  hd.soil = 1;
  int bed = ss_model_add_hfield(m, &hd, &err);
  ss_model_add_plane(m, "ground", -0.05, NULL, 0, &err);
  for (int k = 0; k < 40; k++) {
    ssBodyDef bd = ss_body_def_default();
    char name[32];
    snprintf(name, sizeof name, "b%d", k);
    bd.name = name;
    bd.shape = (ssGeomType)(k % 4);
    bd.size[0] = bd.shape == SS_GEOM_BOX ? 0.4 : 0.2;
    bd.size[1] = 0.3;
    bd.size[2] = 0.2;
    bd.pos[0] = -7 + 14.0 * k / 39;
    bd.pos[1] = (k % 3 - 1) * 1.5;
    bd.pos[2] = 0.4;
    bd.quat[0] = cos(0.1 * k);
    bd.quat[1] = sin(0.1 * k);
    ss_model_add_body(m, &bd, &err);
  }
  ssData *d = ss_data_new(m);
  double *s = calloc((size_t)nx * ny, sizeof *s);
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++) {
      double y = -3 + 6.0 * j / (ny - 1);
      if (fabs(fabs(y) - 0.8) < 0.08 && i < 600) s[j * nx + i] = 0.02 * (1 - fabs(fabs(y) - 0.8) / 0.08);
    }
  ss_soil_set_state(m, d, bed, s, s, NULL, &err);
  free(s);
  free(z);

  ssRenderOptions o = ss_render_options_default();
  ssRenderer *r = ss_render_new(m, &o, &err);
  if (!ok(r != NULL, "1280x720 renderer for the timing scene")) {
    ss_data_free(d);
    ss_model_free(m);
    return;
  }
  unsigned char *a = malloc((size_t)o.width * o.height * 4);
  double t0 = now_s();
  ss_render_pixels(r, m, d, a, &err); /* the first frame compiles shaders */
  double first = now_s() - t0;
  int frames = 2, failed = 0;
  t0 = now_s();
  double c0 = cpu_s();
  for (int k = 0; k < frames; k++)
    if (ss_render_pixels(r, m, d, a, &err) != SS_OK) failed++;
  double per = (now_s() - t0) / frames, per_cpu = (cpu_s() - c0) / frames;
  diag("801x301 bed + 40 primitives, 1280x720: first frame %.0f ms, then %.1f ms/frame "
       "(%.1f ms CPU/frame)",
       first * 1e3, per * 1e3, per_cpu * 1e3);
  ok(failed == 0, "the vehicle-sized scene renders at 1280x720");
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, m, d, out_path("big.png"), &err);
  ss_render_free(r);

  /* a close-up only draws the tiles it sees */
  o.camera_given = 1;
  o.camera_pos[0] = -6;
  o.camera_pos[1] = -2.5;
  o.camera_pos[2] = 1.2;
  o.camera_look_at[0] = -5;
  o.camera_look_at[1] = -0.8;
  o.camera_look_at[2] = 0;
  r = ss_render_new(m, &o, &err);
  ss_render_pixels(r, m, d, a, &err);
  t0 = now_s();
  c0 = cpu_s();
  for (int k = 0; k < frames; k++) ss_render_pixels(r, m, d, a, &err);
  diag("close-up of the same scene: %.1f ms/frame (%.1f ms CPU/frame)",
       (now_s() - t0) / frames * 1e3, (cpu_s() - c0) / frames * 1e3);
  if (getenv("SS_TEST_KEEP")) ss_render_frame(r, m, d, out_path("closeup.png"), &err);
  ss_render_free(r);
  o.camera_given = 0;
  o.width = 800;
  o.height = 400;
  if (getenv("SS_TEST_KEEP"))
    ss_render_rut_map(m, d, bed, 0, 1280, 560, out_path("big_ruts.png"), &err);
  free(a);
  ss_data_free(d);
  ss_model_free(m);
}

int main(void)
{
  const char *keep = getenv("SS_TEST_KEEP");
  if (keep && *keep) {
    snprintf(outdir, sizeof outdir, "%s", keep);
  } else {
    snprintf(outdir, sizeof outdir, "/tmp/ss_test_render_XXXXXX");
    if (!mkdtemp(outdir)) {
      printf("Bail out! cannot make a temporary folder\n");
      return 1;
    }
  }
  test_png_io();
  test_colormap();
  test_bad_sizes();
  test_rut_map_sizes();
  test_frame();
  test_far_from_origin();
  test_follow();
  test_plane();
  test_auto_camera();
  test_mesh_visuals();
  test_buggy_visuals();
  test_gl_backends();
  test_rut_map();
  test_rut_map_title();
  test_plate_scene_rut_map();
  test_timing();
  if (!(keep && *keep)) {
    /* remove what we wrote */
    const char *names[] = {"roundtrip.png", "truncated.png", "frame_000000.png", "ruts.png",
                           "ruts_plastic.png"};
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) unlink(out_path(names[k]));
    rmdir(outdir);
  }
  return done_testing();
}
