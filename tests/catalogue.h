/* catalogue.h -- a catalogue of bad inputs, for the reader tests (include
 * after tap.h).  Every file NAME.EXT in the catalogue's folder starts with
 *   <!-- expect: LINE: SUBSTRING -->
 * and must fail to load with the error at that file and LINE, SUBSTRING in
 * the message and nothing returned.  catalogue_check() walks the files in
 * name order, one TAP line each; slurp() reads a whole file. */
#ifndef SS_CATALOGUE_H
#define SS_CATALOGUE_H
#include "soilsim.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The whole file, NUL-terminated and malloc'd (its size in *len), or NULL. */
static char *slurp(const char *path, size_t *len)
{
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
    free(b);
    b = NULL;
  }
  fclose(f);
  if (b) b[n] = 0;
  if (len) *len = (size_t)n;
  return b;
}

/* Load the file at path, fill *e, free whatever was loaded and set
 * *nothing when the reader returned nothing. */
typedef ssStatus (*catalogueLoad)(const char *path, ssError *e, int *nothing);

static int catalogue_cmp(const void *a, const void *b)
{
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Check every file ending in ext (".xml") in dir, after checking that there
 * are at least `at_least` of them; `what` names them in messages ("scene":
 * "bad-scene catalogue", "bad scenes"). */
static void catalogue_check(const char *dir, const char *ext,
                            const char *what, int at_least, catalogueLoad load)
{
  DIR *dp = opendir(dir);
  if (!ok(dp != NULL, "bad-%s catalogue found at %s", what, dir)) return;
  char **names = NULL;
  int n = 0;
  size_t el = strlen(ext);
  struct dirent *de;
  while ((de = readdir(dp))) {
    size_t l = strlen(de->d_name);
    if (l <= el || strcmp(de->d_name + l - el, ext)) continue;
    char **grown = realloc(names, (size_t)(n + 1) * sizeof *names);
    char *name = strdup(de->d_name);
    if (!grown || !name) {
      free(name);
      if (grown) names = grown;
      ok(0, "out of memory listing the bad-%s catalogue", what);
      break;
    }
    names = grown;
    names[n++] = name;
  }
  closedir(dp);
  qsort(names, (size_t)n, sizeof *names, catalogue_cmp);
  ok(n >= at_least, "catalogue holds %d bad %ss (at least %d)", n, what,
     at_least);
  for (int k = 0; k < n; k++) {
    char path[1400];
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    char *txt = slurp(path, NULL);
    int line = 0, off = 0;
    char want[512] = "";
    if (!txt || sscanf(txt, "<!-- expect: %d: %n", &line, &off) < 1 || off == 0) {
      ok(0, "%s: first line is <!-- expect: LINE: SUBSTRING -->", names[k]);
      free(txt);
      free(names[k]);
      continue;
    }
    const char *s = txt + off, *end = strstr(s, " -->");
    if (end && end - s < (long)sizeof want) memcpy(want, s, (size_t)(end - s));
    free(txt);
    ssError e;
    memset(&e, 0, sizeof e);
    int nothing = 0;
    ssStatus st = load(path, &e, &nothing);
    int good = st != SS_OK && nothing && e.line == line &&
               !strcmp(e.file, path) && want[0] && strstr(e.message, want);
    ok(good, "%s: fails at line %d with '%s'", names[k], line, want);
    if (!good)
      diag("got status %d at %s:%d: %s", (int)st, e.file, e.line, e.message);
    free(names[k]);
  }
  free(names);
}
#endif
