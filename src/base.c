/* base.c -- errors and atomic output files. */
#include "soilsim.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

ssStatus ss_error_set(ssError *err, ssStatus code, const char *file, int line,
                      const char *fmt, ...)
{
  if (!err) return code;
  err->code = code;
  snprintf(err->file, sizeof err->file, "%s", file ? file : "");
  err->line = line;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err->message, sizeof err->message, fmt, ap);
  va_end(ap);
  return code;
}

void ss_error_clear(ssError *err)
{
  if (!err) return;
  memset(err, 0, sizeof *err);
}

const char *ss_status_name(ssStatus code)
{
  switch (code) {
  case SS_OK: return "ok";
  case SS_ERR_NOMEM: return "out of memory";
  case SS_ERR_IO: return "input/output error";
  case SS_ERR_PARSE: return "parse error";
  case SS_ERR_VALUE: return "invalid value";
  case SS_ERR_UNSUPPORTED: return "unsupported";
  case SS_ERR_STATE: return "invalid state";
  case SS_ERR_NUMERIC: return "numerical failure";
  case SS_ERR_NOTFOUND: return "not found";
  }
  return "unknown error";
}

/* The temporary file lives in the destination folder so that rename() is
 * atomic; its name carries the pid so concurrent writers do not collide.
 * O_EXCL | O_NOFOLLOW: a name that exists already (a leftover of a killed
 * run with the same pid, or a link planted there) is never opened; the
 * next suffix is tried instead. */
ssStatus ss_atomic_open(ssAtomicFile *f, const char *path, ssError *err)
{
  memset(f, 0, sizeof *f);
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "empty output path");
  if (strlen(path) >= sizeof f->path)
    return ss_error_set(err, SS_ERR_IO, path, 0, "output path too long");
  snprintf(f->path, sizeof f->path, "%s", path);
  int fd = -1, e = EEXIST;
  for (int k = 0; k < 100 && fd < 0 && e == EEXIST; k++) {
    if (k == 0)
      snprintf(f->tmp_path, sizeof f->tmp_path, "%s.tmp%ld", path, (long)getpid());
    else
      snprintf(f->tmp_path, sizeof f->tmp_path, "%s.tmp%ld.%d", path, (long)getpid(), k);
    fd = open(f->tmp_path, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    e = fd < 0 ? errno : 0;
  }
  if (fd < 0) {
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s", strerror(e));
  }
  FILE *fp = fdopen(fd, "w");
  if (!fp) {
    e = errno;
    close(fd);
    unlink(f->tmp_path);
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s", strerror(e));
  }
  f->fp = fp;
  return SS_OK;
}

int ss_atomic_write(ssAtomicFile *f, const void *buf, size_t n)
{
  if (f->error || !f->fp) return -1;
  if (n == 0) return 0;
  errno = 0;
  if (fwrite(buf, 1, n, f->fp) == n) return 0;
  f->error = errno ? errno : EIO;
  return -1;
}

ssStatus ss_atomic_commit(ssAtomicFile *f, ssError *err)
{
  FILE *fp = f->fp;
  if (!fp)
    return ss_error_set(err, SS_ERR_STATE, f->path, 0, "output file not open");
  /* the reason is the first failure's errno: a failed write (kept by
   * ss_atomic_write), else the flush; never an errno left over from
   * something earlier */
  int e = f->error;
  errno = 0;
  int bad = fflush(fp) != 0;
  if (bad && !e) e = errno;
  if (e || ferror(fp)) bad = 1;
  if (!bad && fsync(fileno(fp)) != 0 && errno != EINVAL) {
    bad = 1;
    e = errno;
  }
  if (fclose(fp) != 0 && !bad) {
    bad = 1;
    e = errno;
  }
  f->fp = NULL;
  if (bad) {
    unlink(f->tmp_path);
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "write failed: %s",
                        strerror(e ? e : EIO));
  }
  if (rename(f->tmp_path, f->path) != 0) {
    e = errno;
    unlink(f->tmp_path);
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "cannot replace file: %s",
                        strerror(e));
  }
  f->tmp_path[0] = 0;
  return SS_OK;
}

void ss_atomic_abort(ssAtomicFile *f)
{
  if (f->fp) {
    fclose(f->fp);
    f->fp = NULL;
  }
  if (f->tmp_path[0]) unlink(f->tmp_path);
  f->tmp_path[0] = 0;
}
