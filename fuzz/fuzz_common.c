/* fuzz_common.c -- a private temporary folder and file writing for the
 * fuzz targets (see fuzz_common.h). */
#include "fuzz_common.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[512];
static int tmpdir_state; /* 0: not tried, 1: made, -1: failed */

/* Remove the folder's files (the targets write no subfolders), then it. */
static void remove_tmpdir(void)
{
  if (tmpdir_state != 1) return;
  DIR *dp = opendir(tmpdir);
  if (dp) {
    struct dirent *de;
    char p[1024];
    while ((de = readdir(dp))) {
      if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
      snprintf(p, sizeof p, "%s/%s", tmpdir, de->d_name);
      unlink(p);
    }
    closedir(dp);
  }
  rmdir(tmpdir);
  tmpdir_state = 0;
}

const char *ss_fuzz_tmpdir(void)
{
  if (tmpdir_state == 0) {
    const char *base = getenv("TMPDIR");
    if (!base || !*base) base = "/tmp";
    snprintf(tmpdir, sizeof tmpdir, "%s/soilsim-fuzz.XXXXXX", base);
    if (mkdtemp(tmpdir)) {
      tmpdir_state = 1;
      atexit(remove_tmpdir);
    } else {
      tmpdir_state = -1;
    }
  }
  return tmpdir_state == 1 ? tmpdir : NULL;
}

int ss_fuzz_write_file(const char *path, const uint8_t *data, size_t len)
{
  int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0) return -1;
  size_t done = 0;
  while (done < len) {
    ssize_t w = write(fd, data + done, len - done);
    if (w <= 0) {
      close(fd);
      return -1;
    }
    done += (size_t)w;
  }
  return close(fd);
}
