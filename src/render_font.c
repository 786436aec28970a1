/* render_font.c -- anti-aliased text labels with FreeType.
 *
 * Each ssFont owns its FT_Library, so fonts in different renderers (or
 * threads) share nothing.  Glyphs are rendered as 8-bit coverage and
 * blended over the image; output is deterministic for a given font file. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif
#include "render.h"

#include <ft2build.h>
#include FT_FREETYPE_H
#include <stdlib.h>
#include <string.h>

#define SS_FONT_FALLBACK "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#ifndef SS_FONT_PATH
#define SS_FONT_PATH SS_FONT_FALLBACK
#endif

struct ssFont {
  FT_Library lib;
  FT_Face face;
  int ascent, descent;
};

void ss_font_free(ssFont *f)
{
  if (!f) return;
  if (f->face) FT_Done_Face(f->face);
  if (f->lib) FT_Done_FreeType(f->lib);
  free(f);
}

ssFont *ss_font_new(int pixel_size, ssError *err)
{
  if (pixel_size < 4) pixel_size = 4;
  ssFont *f = calloc(1, sizeof *f);
  if (!f) {
    ss_error_set(err, SS_ERR_NOMEM, "", 0, "out of memory");
    return NULL;
  }
  if (FT_Init_FreeType(&f->lib) != 0) {
    free(f);
    ss_error_set(err, SS_ERR_UNSUPPORTED, "", 0, "cannot start FreeType");
    return NULL;
  }
  /* SS_FONT_ENV names the font to use, and then it alone is tried (a
   * failure says why); else the configured one, then DejaVu Sans */
  const char *env = getenv(SS_FONT_ENV);
  const char *paths[2] = {SS_FONT_PATH, SS_FONT_FALLBACK};
  int npath = 2;
  if (env && *env) {
    paths[0] = env;
    npath = 1;
  }
  FT_Error fe = 0;
  for (int k = 0; k < npath && !f->face; k++) {
    if (k == 1 && strcmp(paths[0], paths[1]) == 0) break;
    fe = FT_New_Face(f->lib, paths[k], 0, &f->face);
    if (fe != 0) f->face = NULL;
  }
  if (!f->face) {
    if (npath == 1)
      ss_error_set(err, SS_ERR_IO, paths[0], 0,
                   "cannot load the label font named by %s (FreeType error %d)",
                   SS_FONT_ENV, (int)fe);
    else
      ss_error_set(err, SS_ERR_IO, SS_FONT_PATH, 0,
                   "cannot load the label font (FreeType error %d); install "
                   "fonts-dejavu-core or configure --with-font=FILE",
                   (int)fe);
    ss_font_free(f);
    return NULL;
  }
  if (FT_Set_Pixel_Sizes(f->face, 0, (FT_UInt)pixel_size) != 0) {
    ss_error_set(err, SS_ERR_UNSUPPORTED, npath == 1 ? paths[0] : SS_FONT_PATH, 0,
                 "the label font has no %d-pixel size", pixel_size);
    ss_font_free(f);
    return NULL;
  }
  f->ascent = (int)((f->face->size->metrics.ascender + 63) >> 6);
  f->descent = (int)((-f->face->size->metrics.descender + 63) >> 6);
  if (f->descent < 0) f->descent = 0;
  return f;
}

int ss_font_ascent(const ssFont *f) { return f ? f->ascent : 0; }
int ss_font_descent(const ssFont *f) { return f ? f->descent : 0; }

/* Next code point of a UTF-8 string (invalid bytes read as U+FFFD). */
static unsigned long utf8_next(const unsigned char **s)
{
  const unsigned char *p = *s;
  unsigned long c = *p++;
  int extra = 0;
  if (c >= 0xF0 && c < 0xF8) { c &= 0x07; extra = 3; }
  else if (c >= 0xE0) { c &= 0x0F; extra = 2; }
  else if (c >= 0xC0) { c &= 0x1F; extra = 1; }
  else if (c >= 0x80) { *s = p; return 0xFFFD; }
  for (int k = 0; k < extra; k++) {
    if ((*p & 0xC0) != 0x80) { *s = p; return 0xFFFD; }
    c = (c << 6) | (*p++ & 0x3F);
  }
  *s = p;
  return c;
}

/* Walk the string; draw when im is non-NULL.  Returns the advance width. */
static int layout_text(ssFont *f, ssImage *im, int x, int y, const char *text,
                       const unsigned char rgb[3])
{
  if (!f || !text) return 0;
  FT_Face face = f->face;
  int use_kern = FT_HAS_KERNING(face) ? 1 : 0;
  FT_UInt prev = 0;
  long pen = 0; /* 26.6 fixed point */
  const unsigned char *s = (const unsigned char *)text;
  while (*s) {
    unsigned long cp = utf8_next(&s);
    FT_UInt gi = FT_Get_Char_Index(face, cp);
    if (use_kern && prev && gi) {
      FT_Vector k;
      if (FT_Get_Kerning(face, prev, gi, FT_KERNING_DEFAULT, &k) == 0)
        pen += k.x;
    }
    FT_Int32 flags = im ? FT_LOAD_RENDER : FT_LOAD_DEFAULT;
    if (FT_Load_Glyph(face, gi, flags) != 0) {
      prev = 0;
      continue;
    }
    FT_GlyphSlot g = face->glyph;
    if (im && g->bitmap.pixel_mode == FT_PIXEL_MODE_GRAY) {
      int ox = x + (int)((pen + 32) >> 6) + g->bitmap_left;
      int oy = y - g->bitmap_top;
      for (unsigned r = 0; r < g->bitmap.rows; r++) {
        int py = oy + (int)r;
        if (py < 0 || py >= im->h) continue;
        const unsigned char *src = g->bitmap.buffer + (long)r * g->bitmap.pitch;
        for (unsigned c = 0; c < g->bitmap.width; c++) {
          int px = ox + (int)c;
          unsigned a = src[c];
          if (px < 0 || px >= im->w || a == 0) continue;
          unsigned char *d = im->rgba + ((size_t)py * (size_t)im->w + (size_t)px) * 4;
          for (int k = 0; k < 3; k++)
            d[k] = (unsigned char)((d[k] * (255u - a) + rgb[k] * a + 127u) / 255u);
          d[3] = 255;
        }
      }
    }
    pen += g->advance.x;
    prev = gi;
  }
  return (int)((pen + 32) >> 6);
}

int ss_font_width(ssFont *f, const char *text)
{
  return layout_text(f, NULL, 0, 0, text, NULL);
}

void ss_font_draw(ssFont *f, ssImage *im, int x, int y, const char *text,
                  const unsigned char rgb[3])
{
  if (!im) return;
  layout_text(f, im, x, y, text, rgb);
}
