/* png_io.h -- PNG reading and writing with libpng.  Row 0 is the top row of
 * the image.  Writers are atomic (temporary file, then rename). */
#ifndef SS_PNG_IO_H
#define SS_PNG_IO_H

#include "soilsim.h"

/* Read any PNG as grey values in [0, 1] (colour images are converted to
 * luminance; 16-bit precision kept).  *values is malloc'd (w*h). */
ssStatus ss_png_read_gray(const char *path, int *w, int *h, double **values,
                          ssError *err);
/* Read any PNG as 8-bit RGBA.  *rgba is malloc'd (w*h*4). */
ssStatus ss_png_read_rgba(const char *path, int *w, int *h,
                          unsigned char **rgba, ssError *err);
/* Write 8-bit RGBA (w*h*4), atomically. */
ssStatus ss_png_write_rgba(const char *path, int w, int h,
                           const unsigned char *rgba, ssError *err);
/* The same into an output opened with ss_atomic_open, left open: the
 * caller commits it (or aborts it on failure). */
ssStatus ss_png_write_rgba_to(ssAtomicFile *af, int w, int h,
                              const unsigned char *rgba, ssError *err);

#endif /* SS_PNG_IO_H */
