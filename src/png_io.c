/* png_io.c -- PNG reading and writing with libpng (classic API).
 *
 * libpng reports errors by longjmp.  Each reader and writer keeps every
 * object that must survive the jump in a context struct owned by its caller,
 * so nothing the error path frees lives in an automatic variable that
 * setjmp/longjmp could leave indeterminate.  libpng's default handlers print
 * to stderr; ours record the message instead (library code never prints).
 *
 * Hostile files: the signature is checked first, width and height are
 * capped before any image memory is allocated (w*h <= SS_PNG_MAX_PIXELS),
 * ancillary chunks are capped by libpng's chunk-size limit, and a truncated
 * or corrupt stream ends in a clean SS_ERR_PARSE. */
#include "png_io.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* 2^28 pixels: a 16384 x 16384 image, the largest we ever need to read. */
#define SS_PNG_MAX_PIXELS (1L << 28)
/* Per-side cap handed to libpng (its own default is 1e6). */
#define SS_PNG_MAX_SIDE 0x100000u
/* Largest ancillary chunk we accept (text, ICC profiles, ...). */
#define SS_PNG_MAX_CHUNK (8u << 20)

/* Luminance weights for colour images (Rec. 709 / sRGB primaries). */
#define SS_LUMA_R 0.2126
#define SS_LUMA_G 0.7152
#define SS_LUMA_B 0.0722

/* Room for libpng's error message. */
#define SS_PNG_MSG 256

typedef struct pngCtx {
  const char *path;
  FILE *fp;
  png_structp png;
  png_infop info;
  unsigned char *pixels;   /* decoded image, rowbytes * h */
  png_bytep *rows;         /* (h) row pointers into pixels */
  char msg[SS_PNG_MSG];    /* libpng's error message */
  /* results of the read */
  png_uint_32 w, h;
  int channels;            /* after transforms: 1 (G), 2 (GA), 3, 4 */
  int bit_depth;           /* after transforms: 8 or 16 */
  size_t rowbytes;
} pngCtx;

/* The error pointer is the context's msg buffer (SS_PNG_MSG bytes). */
static void png_error_cb(png_structp png, png_const_charp msg)
{
  char *buf = (char *)png_get_error_ptr(png);
  if (buf) snprintf(buf, SS_PNG_MSG, "%s", msg ? msg : "libpng error");
  png_longjmp(png, 1);
}

static void png_warning_cb(png_structp png, png_const_charp msg)
{
  (void)png;
  (void)msg; /* warnings are not errors; stay silent */
}

static void ctx_release_read(pngCtx *c)
{
  if (c->png) png_destroy_read_struct(&c->png, c->info ? &c->info : NULL, NULL);
  c->png = NULL;
  c->info = NULL;
  free(c->rows);
  c->rows = NULL;
  free(c->pixels);
  c->pixels = NULL;
  if (c->fp) fclose(c->fp);
  c->fp = NULL;
}

/* The part of the read that libpng may longjmp out of.  Returns 0 on
 * success, 1 after a libpng error (c->msg says why), 2 when the image is
 * too large, 3 when memory ran out. */
static int decode_png(pngCtx *c)
{
  if (setjmp(png_jmpbuf(c->png))) return 1;

  png_init_io(c->png, c->fp);
  png_set_sig_bytes(c->png, 8);
  png_set_user_limits(c->png, SS_PNG_MAX_SIDE, SS_PNG_MAX_SIDE);
  png_set_chunk_malloc_max(c->png, SS_PNG_MAX_CHUNK);
  png_read_info(c->png, c->info);

  png_uint_32 w = 0, h = 0;
  int depth = 0, ctype = 0, interlace = 0;
  png_get_IHDR(c->png, c->info, &w, &h, &depth, &ctype, &interlace, NULL, NULL);
  c->w = w;
  c->h = h;
  if (w == 0 || h == 0 || (double)w * (double)h > (double)SS_PNG_MAX_PIXELS)
    return 2;

  /* normalise to 8- or 16-bit grey / grey-alpha / RGB / RGBA */
  if (ctype == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(c->png);
  if (ctype == PNG_COLOR_TYPE_GRAY && depth < 8)
    png_set_expand_gray_1_2_4_to_8(c->png);
  if (png_get_valid(c->png, c->info, PNG_INFO_tRNS))
    png_set_tRNS_to_alpha(c->png);
  if (interlace != PNG_INTERLACE_NONE) png_set_interlace_handling(c->png);
  png_read_update_info(c->png, c->info);

  c->channels = png_get_channels(c->png, c->info);
  c->bit_depth = png_get_bit_depth(c->png, c->info);
  c->rowbytes = png_get_rowbytes(c->png, c->info);
  if (c->channels < 1 || c->channels > 4 ||
      (c->bit_depth != 8 && c->bit_depth != 16) ||
      c->rowbytes < (size_t)w * (size_t)c->channels * (size_t)(c->bit_depth / 8))
    png_error(c->png, "unsupported pixel layout");

  c->pixels = malloc(c->rowbytes * (size_t)h);
  c->rows = malloc(sizeof *c->rows * (size_t)h);
  if (!c->pixels || !c->rows) return 3;
  for (png_uint_32 y = 0; y < h; y++) c->rows[y] = c->pixels + c->rowbytes * y;

  png_read_image(c->png, c->rows);
  png_read_end(c->png, NULL);
  return 0;
}

/* Open, check the signature and decode path into c (8/16-bit, 1-4 channels).
 * On failure everything is released and err is filled. */
static ssStatus read_png(pngCtx *c, const char *path, ssError *err)
{
  memset(c, 0, sizeof *c);
  c->path = path;
  if (!path) return ss_error_set(err, SS_ERR_VALUE, "", 0, "no PNG path given");
  /* O_NONBLOCK: opening a FIFO must not wait for a writer (it would hang
   * for ever); anything but a regular file is refused */
  int fd = open(path, O_RDONLY | O_NONBLOCK);
  if (fd < 0)
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot open PNG file: %s",
                        strerror(errno));
  struct stat sb;
  if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    close(fd);
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "cannot read PNG file: not a regular file");
  }
  int fl = fcntl(fd, F_GETFL);
  if (fl != -1) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
  c->fp = fdopen(fd, "rb");
  if (!c->fp) {
    int e = errno;
    close(fd);
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot open PNG file: %s",
                        strerror(e));
  }

  unsigned char sig[8];
  size_t got = fread(sig, 1, sizeof sig, c->fp);
  if (got != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
    ctx_release_read(c);
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        got < sizeof sig ? "not a PNG file (too short)"
                                         : "not a PNG file (bad signature)");
  }

  c->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, c->msg, png_error_cb,
                                  png_warning_cb);
  if (c->png) c->info = png_create_info_struct(c->png);
  if (!c->png || !c->info) {
    ctx_release_read(c);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory starting the PNG decoder");
  }

  int rc = decode_png(c);
  if (rc != 0) {
    ssStatus code;
    if (rc == 2)
      code = ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "PNG image too large: %lu x %lu pixels (at most %ld "
                          "pixels allowed)",
                          (unsigned long)c->w, (unsigned long)c->h,
                          (long)SS_PNG_MAX_PIXELS);
    else if (rc == 3)
      code = ss_error_set(err, SS_ERR_NOMEM, path, 0,
                          "out of memory decoding a %lu x %lu PNG image",
                          (unsigned long)c->w, (unsigned long)c->h);
    else
      code = ss_error_set(err, SS_ERR_PARSE, path, 0,
                          "corrupt or truncated PNG file: %s",
                          c->msg[0] ? c->msg : "decoder error");
    ctx_release_read(c);
    return code;
  }
  return SS_OK;
}

/* Sample k of pixel x in row y, scaled to [0, 1]. */
static double sample01(const pngCtx *c, png_uint_32 x, png_uint_32 y, int k)
{
  const unsigned char *p = c->rows[y];
  if (c->bit_depth == 16) {
    size_t o = ((size_t)x * (size_t)c->channels + (size_t)k) * 2;
    return (double)((p[o] << 8) | p[o + 1]) / 65535.0;
  }
  return (double)p[(size_t)x * (size_t)c->channels + (size_t)k] / 255.0;
}

/* Sample k of pixel x in row y as 8 bits (16-bit samples rounded). */
static unsigned char sample8(const pngCtx *c, png_uint_32 x, png_uint_32 y, int k)
{
  const unsigned char *p = c->rows[y];
  if (c->bit_depth == 16) {
    size_t o = ((size_t)x * (size_t)c->channels + (size_t)k) * 2;
    unsigned v = (unsigned)((p[o] << 8) | p[o + 1]);
    return (unsigned char)((v * 255u + 32767u) / 65535u);
  }
  return p[(size_t)x * (size_t)c->channels + (size_t)k];
}

ssStatus ss_png_read_gray(const char *path, int *w, int *h, double **values,
                          ssError *err)
{
  if (!w || !h || !values)
    return ss_error_set(err, SS_ERR_VALUE, path ? path : "", 0,
                        "ss_png_read_gray: NULL output argument");
  *values = NULL;
  *w = *h = 0;
  pngCtx c;
  ssStatus st = read_png(&c, path, err);
  if (st != SS_OK) return st;

  double *v = malloc(sizeof *v * (size_t)c.w * (size_t)c.h);
  if (!v) {
    ctx_release_read(&c);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory for %lu x %lu grey values",
                        (unsigned long)c.w, (unsigned long)c.h);
  }
  /* alpha is ignored: a height map has no transparency */
  int colour = c.channels >= 3;
  for (png_uint_32 y = 0; y < c.h; y++)
    for (png_uint_32 x = 0; x < c.w; x++) {
      double g;
      if (colour)
        g = SS_LUMA_R * sample01(&c, x, y, 0) + SS_LUMA_G * sample01(&c, x, y, 1) +
            SS_LUMA_B * sample01(&c, x, y, 2);
      else
        g = sample01(&c, x, y, 0);
      if (g > 1.0) g = 1.0;
      v[(size_t)y * c.w + x] = g;
    }
  *w = (int)c.w;
  *h = (int)c.h;
  *values = v;
  ctx_release_read(&c);
  return SS_OK;
}

ssStatus ss_png_read_rgba(const char *path, int *w, int *h,
                          unsigned char **rgba, ssError *err)
{
  if (!w || !h || !rgba)
    return ss_error_set(err, SS_ERR_VALUE, path ? path : "", 0,
                        "ss_png_read_rgba: NULL output argument");
  *rgba = NULL;
  *w = *h = 0;
  pngCtx c;
  ssStatus st = read_png(&c, path, err);
  if (st != SS_OK) return st;

  unsigned char *out = malloc((size_t)c.w * (size_t)c.h * 4);
  if (!out) {
    ctx_release_read(&c);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory for a %lu x %lu RGBA image",
                        (unsigned long)c.w, (unsigned long)c.h);
  }
  for (png_uint_32 y = 0; y < c.h; y++)
    for (png_uint_32 x = 0; x < c.w; x++) {
      unsigned char *o = out + ((size_t)y * c.w + x) * 4;
      switch (c.channels) {
      case 1:
        o[0] = o[1] = o[2] = sample8(&c, x, y, 0);
        o[3] = 255;
        break;
      case 2:
        o[0] = o[1] = o[2] = sample8(&c, x, y, 0);
        o[3] = sample8(&c, x, y, 1);
        break;
      case 3:
        for (int k = 0; k < 3; k++) o[k] = sample8(&c, x, y, k);
        o[3] = 255;
        break;
      default:
        for (int k = 0; k < 4; k++) o[k] = sample8(&c, x, y, k);
        break;
      }
    }
  *w = (int)c.w;
  *h = (int)c.h;
  *rgba = out;
  ctx_release_read(&c);
  return SS_OK;
}

typedef struct pngWriteCtx {
  png_structp png;
  png_infop info;
  char msg[SS_PNG_MSG];
} pngWriteCtx;

static int encode_png(pngWriteCtx *c, FILE *fp, int w, int h,
                      const unsigned char *rgba)
{
  if (setjmp(png_jmpbuf(c->png))) return 1;
  png_init_io(c->png, fp);
  /* opaque images (every rendered frame) are stored as RGB: a quarter less
   * to compress and to store; they decode to the same RGBA pixels */
  int opaque = 1;
  size_t n = (size_t)w * (size_t)h;
  for (size_t k = 0; k < n && opaque; k++) opaque = rgba[4 * k + 3] == 255;
  png_set_IHDR(c->png, c->info, (png_uint_32)w, (png_uint_32)h, 8,
               opaque ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGB_ALPHA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  /* fast, still well compressed: rendered frames are written often */
  png_set_compression_level(c->png, 3);
  png_write_info(c->png, c->info);
  /* the rows stay RGBA in memory; libpng drops the fourth byte */
  if (opaque) png_set_filler(c->png, 0, PNG_FILLER_AFTER);
  for (int y = 0; y < h; y++)
    png_write_row(c->png, (png_const_bytep)(rgba + (size_t)y * (size_t)w * 4));
  png_write_end(c->png, NULL);
  return 0;
}

/* the image a writer is given: pixels, and a size each side >= 1 within
 * SS_PNG_MAX_PIXELS (checked before a file is opened, and again by the
 * writer into an open one) */
static ssStatus check_image(const char *path, int w, int h, const unsigned char *rgba,
                            ssError *err)
{
  if (!rgba)
    return ss_error_set(err, SS_ERR_VALUE, path, 0, "no pixels to write");
  if (w <= 0 || h <= 0 || (double)w * (double)h > (double)SS_PNG_MAX_PIXELS)
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "invalid PNG size %d x %d (each side >= 1, at most %ld "
                        "pixels)",
                        w, h, (long)SS_PNG_MAX_PIXELS);
  return SS_OK;
}

ssStatus ss_png_write_rgba_to(ssAtomicFile *af, int w, int h,
                              const unsigned char *rgba, ssError *err)
{
  const char *path = af && af->path[0] ? af->path : "";
  if (!af || !af->fp)
    return ss_error_set(err, SS_ERR_STATE, path, 0, "PNG output not open");
  ssStatus bad = check_image(path, w, h, rgba, err);
  if (bad != SS_OK) return bad;

  pngWriteCtx c;
  memset(&c, 0, sizeof c);
  c.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, c.msg, png_error_cb,
                                  png_warning_cb);
  if (c.png) c.info = png_create_info_struct(c.png);
  if (!c.png || !c.info) {
    if (c.png) png_destroy_write_struct(&c.png, c.info ? &c.info : NULL);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory starting the PNG encoder");
  }
  errno = 0;
  int rc = encode_png(&c, (FILE *)af->fp, w, h, rgba);
  /* libpng says only "Write Error" when fwrite fails: the system's reason
   * (a full disk, say) is in errno */
  int write_errno = rc != 0 && ferror((FILE *)af->fp) ? errno : 0;
  png_destroy_write_struct(&c.png, &c.info);
  if (rc != 0) {
    if (write_errno)
      return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write PNG file: %s",
                          strerror(write_errno));
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write PNG file: %s",
                        c.msg[0] ? c.msg : "encoder error");
  }
  return SS_OK;
}

ssStatus ss_png_write_rgba(const char *path, int w, int h,
                           const unsigned char *rgba, ssError *err)
{
  if (!path)
    return ss_error_set(err, SS_ERR_VALUE, "", 0, "no PNG path given");
  ssStatus bad = check_image(path, w, h, rgba, err);
  if (bad != SS_OK) return bad;

  ssAtomicFile af;
  memset(&af, 0, sizeof af);
  ssStatus st = ss_atomic_open(&af, path, err);
  if (st != SS_OK) return st;
  st = ss_png_write_rgba_to(&af, w, h, rgba, err);
  if (st != SS_OK) {
    ss_atomic_abort(&af);
    return st;
  }
  return ss_atomic_commit(&af, err);
}
