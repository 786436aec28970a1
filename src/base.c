/* base.c -- errors, paths and atomic output files. */
/* realpath() is XSI, beyond the _POSIX_C_SOURCE the build sets */
#define _XOPEN_SOURCE 700
#include "soilsim.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
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

/* ---------------------------------------------------------------------- */
/* paths                                                                   */

/* dir (consumed) with the path component last[0..n) appended: "." adds
 * nothing and ".." takes dir's last component off (dir has no links to
 * resolve first: it came from realpath, or does not exist).  NULL when
 * out of memory. */
static char *append_component(char *dir, const char *last, size_t n)
{
  if (n == 0 || (n == 1 && last[0] == '.')) return dir;
  if (n == 2 && last[0] == '.' && last[1] == '.') {
    char *slash = strrchr(dir, '/');
    if (slash == dir) slash[1] = 0;
    else if (slash) *slash = 0;
    return dir;
  }
  size_t d = strlen(dir);
  size_t sep = d > 0 && dir[d - 1] != '/';
  char *r = malloc(d + sep + n + 1);
  if (r) {
    memcpy(r, dir, d);
    if (sep) r[d] = '/';
    memcpy(r + d + sep, last, n);
    r[d + sep + n] = 0;
  }
  free(dir);
  return r;
}

/* ss_path_absolute (soilsim.h), depth the links and folders followed so
 * far */
static char *path_absolute(const char *path, int depth)
{
  char *r = realpath(path, NULL);
  if (r) return r;
  if (depth > 64) return strdup(path); /* a cycle, or a folder deleted under us */
  struct stat ls;
  char link[PATH_MAX];
  ssize_t nl;
  if (lstat(path, &ls) == 0 && S_ISLNK(ls.st_mode) &&
      (nl = readlink(path, link, sizeof link - 1)) > 0) {
    link[nl] = 0;
    const char *slash = strrchr(path, '/');
    size_t keep = link[0] == '/' || !slash ? 0 : (size_t)(slash - path) + 1;
    char *t = malloc(keep + (size_t)nl + 1);
    if (!t) return NULL;
    memcpy(t, path, keep);
    memcpy(t + keep, link, (size_t)nl + 1);
    r = path_absolute(t, depth + 1);
    free(t);
    return r;
  }
  size_t n = strlen(path);
  while (n > 1 && path[n - 1] == '/') n--;
  size_t b = n;
  while (b > 0 && path[b - 1] != '/') b--;
  char *dir = b ? strndup(path, b) : strdup(".");
  if (!dir) return NULL;
  char *pd = path_absolute(dir, depth + 1);
  free(dir);
  return pd ? append_component(pd, path + b, n - b) : NULL;
}

char *ss_path_absolute(const char *path)
{
  return path && *path ? path_absolute(path, 0) : NULL;
}

/* ---------------------------------------------------------------------- */
/* output files                                                            */

enum { OUTPUT_NEW, OUTPUT_REPLACE, OUTPUT_STREAM };

/* f->target: path with the symbolic links of its last component followed,
 * as open() would follow them (a relative link is read from the link's
 * folder); 0 or an errno. */
static int follow_links(ssAtomicFile *f)
{
  char *t = f->target;
  size_t cap = sizeof f->target;
  snprintf(t, cap, "%s", f->path);
  for (int hops = 0;; hops++) {
    struct stat ls;
    if (lstat(t, &ls) != 0 || !S_ISLNK(ls.st_mode)) return 0;
    if (hops == 40) return ELOOP;
    char link[sizeof f->target];
    ssize_t n = readlink(t, link, sizeof link);
    if (n < 0) return errno;
    if ((size_t)n >= sizeof link) return ENAMETOOLONG;
    link[n] = 0;
    char *slash = strrchr(t, '/');
    size_t keep = link[0] == '/' || !slash ? 0 : (size_t)(slash - t) + 1;
    if (keep + (size_t)n >= cap) return ENAMETOOLONG;
    memcpy(t + keep, link, (size_t)n + 1);
  }
}

/* What path is (see ss_atomic_open): fills f->path and f->target, *kind
 * and, for a file to replace, *st. */
static ssStatus atomic_resolve(ssAtomicFile *f, const char *path,
                               struct stat *st, int *kind, ssError *err)
{
  memset(f, 0, sizeof *f);
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "empty output path");
  if (strlen(path) >= sizeof f->path)
    return ss_error_set(err, SS_ERR_IO, path, 0, "output path too long");
  snprintf(f->path, sizeof f->path, "%s", path);
  if (stat(path, st) == 0) {
    if (S_ISCHR(st->st_mode) || S_ISFIFO(st->st_mode)) {
      /* /dev/stdout of a pipe leads to "pipe:[N]", no path: never follow
       * a stream's links, open it by the name given */
      snprintf(f->target, sizeof f->target, "%s", path);
      *kind = OUTPUT_STREAM;
      return SS_OK;
    }
    if (S_ISDIR(st->st_mode))
      return ss_error_set(err, SS_ERR_IO, path, 0,
                          "cannot write: is a directory");
    if (!S_ISREG(st->st_mode))
      return ss_error_set(err, SS_ERR_IO, path, 0,
                          "cannot write: not a regular file, character "
                          "device or FIFO");
    *kind = OUTPUT_REPLACE;
  } else if (errno == ENOENT) {
    *kind = OUTPUT_NEW; /* nothing there, or a link to nothing yet */
  } else {
    int e = errno;
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s",
                        strerror(e));
  }
  int e = follow_links(f);
  if (e)
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s",
                        strerror(e));
  return SS_OK;
}

/* The temporary file takes the replaced file's owner and group where the
 * system allows (root; a group the writer is in), as sed -i does, then
 * its permission bits (rwx only: no set-id bit is passed on to new
 * contents).  0, or -1 with errno when the bits cannot be set. */
static int keep_owner_and_mode(int fd, const struct stat *st)
{
  if ((st->st_uid != geteuid() || st->st_gid != getegid()) &&
      fchown(fd, st->st_uid, st->st_gid) != 0 &&
      fchown(fd, (uid_t)-1, st->st_gid) != 0) {
    /* the writer's owner and group, as for a new file */
  }
  return fchmod(fd, st->st_mode & 0777);
}

/* A character device or FIFO, opened in place for writing (a FIFO waits
 * for its reader, as a shell's > does). */
static ssStatus open_stream(ssAtomicFile *f, ssError *err)
{
  int fd = open(f->path, O_WRONLY | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    int e = errno;
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "cannot write: %s",
                        strerror(e));
  }
  /* the name may have been replaced since the stat: never write into the
   * middle of a regular file that took its place */
  struct stat st;
  if (fstat(fd, &st) != 0 || !(S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
    close(fd);
    return ss_error_set(err, SS_ERR_IO, f->path, 0,
                        "cannot write: changed while being opened");
  }
  FILE *fp = fdopen(fd, "w");
  if (!fp) {
    int e = errno;
    close(fd);
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "cannot write: %s",
                        strerror(e));
  }
  f->fp = fp;
  f->direct = 1;
  return SS_OK;
}

/* The behaviour is described in soilsim.h.  The temporary file
 * TARGET.tmpPID (TARGET.tmpPID.K when that name is taken) lives in the
 * destination's folder so that rename() is atomic; its name carries the
 * pid so concurrent writers do not collide.  O_EXCL | O_NOFOLLOW: a name
 * that exists already (a leftover of a killed run with the same pid, or a
 * link planted there) is never opened; the next suffix is tried instead. */
ssStatus ss_atomic_open(ssAtomicFile *f, const char *path, ssError *err)
{
  struct stat st;
  int kind = OUTPUT_NEW;
  ssStatus s = atomic_resolve(f, path, &st, &kind, err);
  if (s != SS_OK) return s;
  if (kind == OUTPUT_STREAM) return open_stream(f, err);

  /* the name's last component, cut so that with the suffix it stays a
   * legal name (NAME_MAX): an output named with 246 to 255 characters
   * failed with "File name too long" for its temporary file alone */
  const char *slash = strrchr(f->target, '/');
  size_t base = slash ? (size_t)(slash - f->target) + 1 : 0, len = strlen(f->target) - base;
  int fd = -1, e = EEXIST;
  for (int k = 0; k < 100 && fd < 0 && e == EEXIST; k++) {
    char suffix[48];
    if (k == 0)
      snprintf(suffix, sizeof suffix, ".tmp%ld", (long)getpid());
    else
      snprintf(suffix, sizeof suffix, ".tmp%ld.%d", (long)getpid(), k);
    size_t keep = len + strlen(suffix) > NAME_MAX ? NAME_MAX - strlen(suffix) : len;
    snprintf(f->tmp_path, sizeof f->tmp_path, "%.*s%s", (int)(base + keep), f->target, suffix);
    fd = open(f->tmp_path, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    e = fd < 0 ? errno : 0;
  }
  if (fd < 0) {
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s", strerror(e));
  }
  if (kind == OUTPUT_REPLACE && keep_owner_and_mode(fd, &st) != 0) {
    e = errno;
    close(fd);
    unlink(f->tmp_path);
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "cannot keep the file's permissions: %s", strerror(e));
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

ssStatus ss_atomic_check(const char *path, ssError *err)
{
  ssAtomicFile f;
  struct stat st;
  int kind = OUTPUT_NEW;
  ssStatus s = atomic_resolve(&f, path, &st, &kind, err);
  if (s != SS_OK) return s;
  if (kind == OUTPUT_STREAM) {
    /* not opened: a FIFO would wait for its reader here, and closing it
     * again would hand the reader an end of file before the output */
    if (access(path, W_OK) != 0) {
      int e = errno;
      return ss_error_set(err, SS_ERR_IO, path, 0, "cannot write: %s",
                          strerror(e));
    }
    return SS_OK;
  }
  s = ss_atomic_open(&f, path, err);
  if (s == SS_OK) ss_atomic_abort(&f);
  return s;
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
  /* a stream has nothing to sync (fsync fails with EINVAL on pipes) */
  if (!bad && !f->direct && fsync(fileno(fp)) != 0 && errno != EINVAL) {
    bad = 1;
    e = errno;
  }
  if (fclose(fp) != 0 && !bad) {
    bad = 1;
    e = errno;
  }
  f->fp = NULL;
  if (bad) {
    if (f->tmp_path[0]) unlink(f->tmp_path);
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "write failed: %s",
                        strerror(e ? e : EIO));
  }
  if (f->direct) return SS_OK;
  if (rename(f->tmp_path, f->target) != 0) {
    e = errno;
    unlink(f->tmp_path);
    f->tmp_path[0] = 0;
    return ss_error_set(err, SS_ERR_IO, f->path, 0, "cannot replace file: %s",
                        strerror(e));
  }
  f->tmp_path[0] = 0;
  return SS_OK;
}

/* A stream keeps what has been written to it; stdio's buffer goes out
 * with the close, as it would at exit. */
void ss_atomic_abort(ssAtomicFile *f)
{
  if (f->fp) {
    fclose(f->fp);
    f->fp = NULL;
  }
  if (f->tmp_path[0]) unlink(f->tmp_path);
  f->tmp_path[0] = 0;
}
