/* soilsim.c -- the command-line program (DESIGN 4.3).
 *
 * Reads a world XML scene, checks every argument and output before the
 * first step, steps the world, and writes the requested outputs: an export
 * of the final world, a per-step CSV, rendered frames and a rut map.  Each
 * output file is replaced atomically, so a failed or interrupted run never
 * leaves a half-written file behind (a device or FIFO, /dev/stdout for
 * one, is written in place: see ss_atomic_open).
 *
 * Exit status: 0 success; 1 bad input or a failed run (the message names
 * the file and line); 2 bad usage.  Only this file prints or exits. */
#include "soilsim.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

enum { EXIT_RUN_FAILED = 1, EXIT_USAGE = 2 };

#define DEFAULT_STEPS 1000L
#define DEFAULT_RENDER_EVERY 20L
#define MAX_IMAGE_SIDE 16384L

/* One --checkpoint FILE@STEP request. */
typedef struct CheckpointReq {
  const char *arg; /* the argument as given, for messages */
  char *path;      /* output file (owned) */
  long step;       /* written after this step (and its removals) */
} CheckpointReq;

/* One --remove NAME@STEP request. */
typedef struct Removal {
  const char *arg; /* the argument as given, for messages */
  char *name;      /* system name (owned) */
  long step;       /* remove after this step has been recorded */
} Removal;

typedef struct Options {
  const char *scene;
  long steps;
  const char *export_path;
  const char *csv_path;
  const char *render_dir;
  long render_every;
  int render_every_given;
  int width, height; /* 0: the renderer's default */
  const char *rut_map;
  int quiet;
  Removal *removal;
  int nremoval;
  CheckpointReq *ckpt;
  int nckpt;
  const char *restore;      /* --restore FILE */
  /* solver overrides of the scene's <contact_solver>; < 0 / 0: not given */
  double solver_tolerance;
  long max_sweeps;
  int warm_start;           /* -1 not given, 0 off, 1 on */
  double camera_pos[3], camera_look_at[3], camera_fov; /* 0 fov: default */
  int camera_pos_given, camera_look_given;
  const char *camera_follow;
  int color;                /* 0 default, else ssColorMode + 1 */
} Options;

/* The progress line on stderr (only on a terminal, without --quiet and CI). */
typedef struct Progress {
  int on;
  int drawn;       /* 1 while a line is on screen */
  double start;    /* monotonic time of the first step (s) */
  double last;     /* when the line was last drawn (s) */
} Progress;

static volatile sig_atomic_t g_signal;
static int g_interrupted; /* the run stopped early because of g_signal */

/* ---------------------------------------------------------------------- */
/* messages                                                                */

static void usage(FILE *out)
{
  ssRenderOptions r = ss_render_options_default();
  fprintf(out,
"usage: soilsim SCENE.xml [options]\n"
"Simulate rigid bodies on deformable soil beds described by a world XML scene.\n"
"\n"
"options:\n"
"  --steps N            number of time steps to run (default %ld; 0 = none)\n"
"  --export OUT.xml     write the final world (with soil state) as XML\n"
"  --csv FILE           write one row of statistics and positions per step\n"
"  --remove NAME@STEP   remove body or system NAME after step STEP (repeatable)\n"
"  --render DIR         write frames DIR/frame_NNNNNN.png (created if needed)\n"
"  --render-every K     render every K steps (default %ld; needs --render)\n"
"  --size WxH           image size for --render and --rut-map (default %dx%d)\n"
"  --rut-map FILE.png   write a top-down map of the final plastic sinkage\n"
"  --camera-pos X,Y,Z   camera position for --render (with --camera-look-at)\n"
"  --camera-look-at X,Y,Z\n"
"                       point the camera looks at\n"
"  --camera-fov DEG     vertical field of view, 0 < DEG < 180 (default 45)\n"
"  --camera-follow NAME keep the camera's offset to body or system NAME\n"
"                       (needs --camera-pos or the scene's <camera>)\n"
"  --color MODE         bed colour: sinkage (default), plastic or soil\n"
"  --checkpoint FILE@STEP\n"
"                       write a binary checkpoint after step STEP (repeatable)\n"
"  --restore FILE       start from a checkpoint of this scene's world\n"
"  --solver-tolerance X\n"
"                       solver tolerance, 0 < X < 1 (overrides the scene)\n"
"  --max-sweeps N       Gauss-Seidel sweep cap, 1..1000000 (overrides the scene)\n"
"  --warm-start on|off  terrain warm start (overrides the scene)\n"
"  -q, --quiet          no progress line and no summary; errors only\n"
"  -h, --help           show this help and exit\n"
"  -V, --version        show the version and exit\n"
"\n"
"Options also accept the form --option=VALUE.  Exit status: 0 success,\n"
"1 bad input or failed run, 2 bad usage.  See soilsim(1).\n",
      DEFAULT_STEPS, DEFAULT_RENDER_EVERY, r.width, r.height);
}

/* A usage error: what is wrong, then where to look; exit status 2. */
static int usage_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static int usage_error(const char *fmt, ...)
{
  va_list ap;
  va_start(ap, fmt);
  fputs("soilsim: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputs("\ntry 'soilsim --help'\n", stderr);
  va_end(ap);
  return EXIT_USAGE;
}

/* soilsim: FILE:LINE: error: MESSAGE (FILE and LINE left out when unknown). */
static void report(const ssError *e)
{
  fputs("soilsim: ", stderr);
  if (e->file[0]) {
    if (e->line > 0)
      fprintf(stderr, "%s:%d: ", e->file, e->line);
    else
      fprintf(stderr, "%s: ", e->file);
  }
  fprintf(stderr, "error: %s\n",
          e->message[0] ? e->message : ss_status_name(e->code));
}

/* ---------------------------------------------------------------------- */
/* argument parsing                                                        */

/* Whole-string base-10 integer in [lo, hi]; no spaces, no trailing junk. */
static int parse_long(const char *s, long lo, long hi, long *out)
{
  if (!s || !*s || !((*s >= '0' && *s <= '9') || *s == '+' || *s == '-'))
    return 0;
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (errno || end == s || *end || v < lo || v > hi) return 0;
  *out = v;
  return 1;
}

/* WxH with both sides in [1, MAX_IMAGE_SIDE]. */
static int parse_size(const char *s, int *w, int *h)
{
  const char *x = strpbrk(s, "xX");
  if (!x || x == s) return 0;
  char buf[32];
  size_t n = (size_t)(x - s);
  if (n >= sizeof buf) return 0;
  memcpy(buf, s, n);
  buf[n] = 0;
  long lw, lh;
  if (!parse_long(buf, 1, MAX_IMAGE_SIDE, &lw)) return 0;
  if (!parse_long(x + 1, 1, MAX_IMAGE_SIDE, &lh)) return 0;
  *w = (int)lw;
  *h = (int)lh;
  return 1;
}

enum {
  OPT_STEPS, OPT_EXPORT, OPT_CSV, OPT_REMOVE, OPT_RENDER, OPT_RENDER_EVERY,
  OPT_SIZE, OPT_RUT_MAP, OPT_QUIET, OPT_HELP, OPT_VERSION, OPT_CHECKPOINT,
  OPT_RESTORE, OPT_SOLVER_TOLERANCE, OPT_MAX_SWEEPS, OPT_WARM_START,
  OPT_CAMERA_POS, OPT_CAMERA_LOOK_AT, OPT_CAMERA_FOV, OPT_CAMERA_FOLLOW, OPT_COLOR
};

static const struct OptionSpec {
  const char *name; /* without the leading dashes */
  int id;
  int has_value;
} option_specs[] = {
  {"steps", OPT_STEPS, 1},
  {"export", OPT_EXPORT, 1},
  {"csv", OPT_CSV, 1},
  {"remove", OPT_REMOVE, 1},
  {"render", OPT_RENDER, 1},
  {"render-every", OPT_RENDER_EVERY, 1},
  {"size", OPT_SIZE, 1},
  {"rut-map", OPT_RUT_MAP, 1},
  {"quiet", OPT_QUIET, 0},
  {"help", OPT_HELP, 0},
  {"version", OPT_VERSION, 0},
  {"checkpoint", OPT_CHECKPOINT, 1},
  {"restore", OPT_RESTORE, 1},
  {"solver-tolerance", OPT_SOLVER_TOLERANCE, 1},
  {"max-sweeps", OPT_MAX_SWEEPS, 1},
  {"warm-start", OPT_WARM_START, 1},
  {"camera-pos", OPT_CAMERA_POS, 1},
  {"camera-look-at", OPT_CAMERA_LOOK_AT, 1},
  {"camera-fov", OPT_CAMERA_FOV, 1},
  {"camera-follow", OPT_CAMERA_FOLLOW, 1},
  {"color", OPT_COLOR, 1},
};

static void options_free(Options *o)
{
  for (int i = 0; i < o->nremoval; i++) free(o->removal[i].name);
  free(o->removal);
  o->removal = NULL;
  o->nremoval = 0;
  for (int i = 0; i < o->nckpt; i++) free(o->ckpt[i].path);
  free(o->ckpt);
  o->ckpt = NULL;
  o->nckpt = 0;
}

/* A plain decimal number (digits, point, exponent; no hex, NaN or Inf),
 * finite, strictly between lo and hi. */
static int parse_fraction(const char *s, double lo, double hi, double *out)
{
  if (!s || !*s || strspn(s, "0123456789.eE+-") != strlen(s)) return 0;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (errno || end == s || *end || !isfinite(v) || !(v > lo && v < hi))
    return 0;
  *out = v;
  return 1;
}

/* "x,y,z" or "x y z": three finite numbers, one comma or spaces between
 * two of them (so "1,,2,3" is not read as 1,2,3) */
static int parse_vec3(const char *s, double v[3])
{
  const char *p = s;
  for (int k = 0; k < 3; k++) {
    while (*p == ' ') p++;
    if (k && *p == ',') p++;
    while (*p == ' ') p++;
    if (!*p || *p == ',') return 0;
    char *end;
    errno = 0;
    v[k] = strtod(p, &end);
    if (end == p || errno || !isfinite(v[k])) return 0;
    p = end;
  }
  while (*p == ' ') p++;
  return *p == 0;
}

static int add_checkpoint(Options *o, const char *arg)
{
  const char *at = strrchr(arg, '@');
  long step;
  if (!at || at == arg || !parse_long(at + 1, 0, LONG_MAX, &step))
    return usage_error("invalid --checkpoint value '%s': expected FILE@STEP "
                       "with STEP an integer >= 0", arg);
  /* one file given twice is refused with the other outputs on one file,
   * in check_clashes */
  size_t n = (size_t)(at - arg);
  CheckpointReq *c = realloc(o->ckpt, (size_t)(o->nckpt + 1) * sizeof *c);
  if (!c) {
    fputs("soilsim: error: out of memory\n", stderr);
    return EXIT_RUN_FAILED;
  }
  o->ckpt = c;
  char *path = malloc(n + 1);
  if (!path) {
    fputs("soilsim: error: out of memory\n", stderr);
    return EXIT_RUN_FAILED;
  }
  memcpy(path, arg, n);
  path[n] = 0;
  c[o->nckpt].arg = arg;
  c[o->nckpt].path = path;
  c[o->nckpt].step = step;
  o->nckpt++;
  return -1;
}

static int add_removal(Options *o, const char *arg)
{
  const char *at = strrchr(arg, '@');
  long step;
  if (!at || at == arg || !parse_long(at + 1, 0, LONG_MAX, &step))
    return usage_error("invalid --remove value '%s': expected NAME@STEP "
                       "with STEP an integer >= 0", arg);
  size_t n = (size_t)(at - arg);
  for (int i = 0; i < o->nremoval; i++)
    if (strlen(o->removal[i].name) == n && !memcmp(o->removal[i].name, arg, n))
      return usage_error("--remove names '%.*s' twice ('%s' and '%s')", (int)n,
                         arg, o->removal[i].arg, arg);
  Removal *r = realloc(o->removal, (size_t)(o->nremoval + 1) * sizeof *r);
  if (!r) {
    fputs("soilsim: error: out of memory\n", stderr);
    return EXIT_RUN_FAILED;
  }
  o->removal = r;
  char *name = malloc(n + 1);
  if (!name) {
    fputs("soilsim: error: out of memory\n", stderr);
    return EXIT_RUN_FAILED;
  }
  memcpy(name, arg, n);
  name[n] = 0;
  r[o->nremoval].arg = arg;
  r[o->nremoval].name = name;
  r[o->nremoval].step = step;
  o->nremoval++;
  return -1;
}

/* ---------------------------------------------------------------------- */
/* outputs on one file                                                     */

/* One output, for telling whether two outputs are one file. */
typedef struct OutputName {
  const char *flag; /* "--export", ... */
  const char *arg;  /* as given (a checkpoint's FILE@STEP), for messages */
  char *abs;        /* the normalised absolute path (owned) */
  int exists;       /* dev and ino are those of the file there now */
  dev_t dev;
  ino_t ino;
} OutputName;

static int same_output(const OutputName *a, const OutputName *b)
{
  if (a->exists && b->exists) return a->dev == b->dev && a->ino == b->ino;
  return !strcmp(a->abs, b->abs);
}

/* The separator between folder dir and a name in it: none where dir
 * already ends in '/' (--render fr/ named fr//frame_000000.png) */
static const char *dir_sep(const char *dir)
{
  size_t n = strlen(dir);
  return n && dir[n - 1] == '/' ? "" : "/";
}

/* Whether name is a frame's: frame_%06ld.png, as render_step names them.
 * Every such name in the --render folder is the renderer's, whether or
 * not this run's --steps and --render-every reach that step. */
static int is_frame_name(const char *name)
{
  const char *digits = name + 6, *dot = strrchr(name, '.');
  if (strncmp(name, "frame_", 6) || !dot || strcmp(dot, ".png")) return 0;
  char buf[32], again[32];
  size_t nd = (size_t)(dot - digits);
  if (nd == 0 || nd >= sizeof buf) return 0;
  memcpy(buf, digits, nd);
  buf[nd] = 0;
  long k;
  if (strspn(buf, "0123456789") != nd || !parse_long(buf, 0, LONG_MAX, &k))
    return 0;
  snprintf(again, sizeof again, "%06ld", k);
  return !strcmp(again, buf);
}

/* Two outputs on one file would overwrite each other, one of them lost
 * (or fail after the whole run, when one is the --render folder): a usage
 * error, found before anything is created.  Paths are compared by their
 * absolute form and, where both exist, by device and inode, so e.xml,
 * ./e.xml, a symbolic link to it and a hard link are one file.  --render
 * DIR owns DIR (a folder, with its missing parents) and the frame names
 * in it.  Returns -1, 2, or 1 when out of memory. */
static int check_clashes(const Options *o)
{
  int n = 0, rc = -1;
  OutputName *out = calloc((size_t)o->nckpt + 4, sizeof *out);
  if (!out) goto nomem;
  const char *file[3] = {o->export_path, o->csv_path, o->rut_map};
  const char *flag[3] = {"--export", "--csv", "--rut-map"};
  for (int i = 0; i < 3 + o->nckpt + 1; i++) {
    const char *path, *f, *arg;
    if (i < 3) {
      path = arg = file[i];
      f = flag[i];
    } else if (i < 3 + o->nckpt) {
      path = o->ckpt[i - 3].path;
      arg = o->ckpt[i - 3].arg;
      f = "--checkpoint";
    } else {
      path = arg = o->render_dir; /* last: out[n - 1] when given */
      f = "--render";
    }
    if (!path) continue;
    OutputName *u = &out[n++];
    u->flag = f;
    u->arg = arg;
    u->abs = ss_path_absolute(path);
    if (!u->abs) goto nomem;
    struct stat st;
    if (stat(path, &st) == 0) {
      u->exists = 1;
      u->dev = st.st_dev;
      u->ino = st.st_ino;
    }
  }
  int nfile = o->render_dir ? n - 1 : n;
  for (int i = 0; i < nfile && rc < 0; i++)
    for (int j = i + 1; j < nfile && rc < 0; j++)
      if (same_output(&out[i], &out[j]))
        rc = usage_error("%s '%s' and %s '%s' write the same file",
                         out[i].flag, out[i].arg, out[j].flag, out[j].arg);
  if (o->render_dir && rc < 0) {
    const OutputName *r = &out[n - 1];
    size_t nr = strlen(r->abs);
    for (int i = 0; i < nfile && rc < 0; i++) {
      const OutputName *u = &out[i];
      size_t nu = strlen(u->abs);
      const char *slash = strrchr(u->abs, '/');
      if (same_output(r, u))
        rc = usage_error("--render '%s' and %s '%s' name one path: the "
                         "folder of the frames", r->arg, u->flag, u->arg);
      else if (nu < nr && !strncmp(r->abs, u->abs, nu) &&
               (r->abs[nu] == '/' || u->abs[nu - 1] == '/'))
        rc = usage_error("%s '%s' is a folder of --render '%s'", u->flag,
                         u->arg, r->arg);
      else if (slash && (size_t)(slash - u->abs) == (nr > 1 ? nr : 0) &&
               !strncmp(u->abs, r->abs, nr > 1 ? nr : 0) &&
               is_frame_name(slash + 1))
        rc = usage_error("%s '%s' has the name of a frame of --render '%s'",
                         u->flag, u->arg, r->arg);
    }
  }
  goto done;
nomem:
  fputs("soilsim: error: out of memory\n", stderr);
  rc = EXIT_RUN_FAILED;
done:
  for (int i = 0; i < n; i++) free(out[i].abs);
  free(out);
  return rc;
}

/* Returns -1 to go on running, or the exit status (0 after --help or
 * --version, 2 on bad usage). */
static int parse_args(int argc, char **argv, Options *o)
{
  int steps_given = 0, size_given = 0, only_files = 0;
  memset(o, 0, sizeof *o);
  o->steps = DEFAULT_STEPS;
  o->render_every = DEFAULT_RENDER_EVERY;
  o->solver_tolerance = -1;
  o->warm_start = -1;

  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (only_files || a[0] != '-' || a[1] == 0) {
      if (o->scene)
        return usage_error("more than one scene given ('%s' and '%s')",
                           o->scene, a);
      o->scene = a;
      continue;
    }
    if (!strcmp(a, "--")) {
      only_files = 1;
      continue;
    }

    /* find the option: --name, --name=value, or the short -h / -q / -V */
    const struct OptionSpec *spec = NULL;
    const char *value = NULL;
    size_t namelen = 0;
    if (a[1] == '-') {
      const char *name = a + 2;
      const char *eq = strchr(name, '=');
      namelen = eq ? (size_t)(eq - name) : strlen(name);
      for (size_t k = 0; k < sizeof option_specs / sizeof option_specs[0]; k++)
        if (strlen(option_specs[k].name) == namelen &&
            !strncmp(option_specs[k].name, name, namelen))
          spec = &option_specs[k];
      if (!spec)
        return usage_error("unknown option '--%.*s'", (int)namelen, name);
      if (eq) {
        if (!spec->has_value)
          return usage_error("option '--%s' takes no value", spec->name);
        value = eq + 1;
      }
    } else if (!strcmp(a, "-h")) {
      spec = &option_specs[OPT_HELP];
    } else if (!strcmp(a, "-q")) {
      spec = &option_specs[OPT_QUIET];
    } else if (!strcmp(a, "-V")) {
      spec = &option_specs[OPT_VERSION];
    } else {
      return usage_error("unknown option '%s'", a);
    }

    /* a separate value must not look like the next option */
    if (spec->has_value && !value) {
      if (i + 1 >= argc || !strncmp(argv[i + 1], "--", 2))
        return usage_error("option '--%s' needs a value", spec->name);
      value = argv[++i];
    }
    if (spec->has_value && !*value)
      return usage_error("option '--%s' needs a value", spec->name);

    switch (spec->id) {
    case OPT_STEPS:
      if (!parse_long(value, 0, LONG_MAX - 1, &o->steps))
        return usage_error("invalid --steps value '%s': expected an integer "
                           "from 0 to %ld", value, LONG_MAX - 1);
      steps_given = 1;
      break;
    case OPT_EXPORT: o->export_path = value; break;
    case OPT_CSV: o->csv_path = value; break;
    case OPT_REMOVE: {
      int rc = add_removal(o, value);
      if (rc >= 0) return rc;
      break;
    }
    case OPT_RENDER: o->render_dir = value; break;
    case OPT_RENDER_EVERY:
      if (!parse_long(value, 1, LONG_MAX, &o->render_every))
        return usage_error("invalid --render-every value '%s': expected an "
                           "integer >= 1", value);
      o->render_every_given = 1;
      break;
    case OPT_SIZE:
      if (!parse_size(value, &o->width, &o->height))
        return usage_error("invalid --size value '%s': expected WxH with W "
                           "and H integers from 1 to %ld", value,
                           MAX_IMAGE_SIDE);
      size_given = 1;
      break;
    case OPT_RUT_MAP: o->rut_map = value; break;
    case OPT_CAMERA_POS:
      if (!parse_vec3(value, o->camera_pos))
        return usage_error("invalid --camera-pos value '%s': expected X,Y,Z", value);
      o->camera_pos_given = 1;
      break;
    case OPT_CAMERA_LOOK_AT:
      if (!parse_vec3(value, o->camera_look_at))
        return usage_error("invalid --camera-look-at value '%s': expected X,Y,Z", value);
      o->camera_look_given = 1;
      break;
    case OPT_CAMERA_FOV:
      if (!parse_fraction(value, 0, 180, &o->camera_fov))
        return usage_error("invalid --camera-fov value '%s': expected degrees "
                           "between 0 and 180 (exclusive)", value);
      break;
    case OPT_CAMERA_FOLLOW: o->camera_follow = value; break;
    case OPT_COLOR:
      if (!strcmp(value, "sinkage")) o->color = SS_COLOR_SINKAGE + 1;
      else if (!strcmp(value, "plastic")) o->color = SS_COLOR_PLASTIC + 1;
      else if (!strcmp(value, "soil")) o->color = SS_COLOR_SOIL + 1;
      else
        return usage_error("invalid --color value '%s' (allowed: sinkage, "
                           "plastic, soil)", value);
      break;
    case OPT_CHECKPOINT: {
      int rc = add_checkpoint(o, value);
      if (rc >= 0) return rc;
      break;
    }
    case OPT_RESTORE: o->restore = value; break;
    case OPT_SOLVER_TOLERANCE:
      if (!parse_fraction(value, 0, 1, &o->solver_tolerance))
        return usage_error("invalid --solver-tolerance value '%s': expected a "
                           "number between 0 and 1 (exclusive)", value);
      break;
    case OPT_MAX_SWEEPS:
      if (!parse_long(value, 1, 1000000, &o->max_sweeps))
        return usage_error("invalid --max-sweeps value '%s': expected an "
                           "integer from 1 to 1000000", value);
      break;
    case OPT_WARM_START:
      if (!strcmp(value, "on"))
        o->warm_start = 1;
      else if (!strcmp(value, "off"))
        o->warm_start = 0;
      else
        return usage_error("invalid --warm-start value '%s': expected 'on' "
                           "or 'off'", value);
      break;
    case OPT_QUIET: o->quiet = 1; break;
    case OPT_HELP:
      usage(stdout);
      return 0;
    case OPT_VERSION:
      printf("soilsim %s\n", SS_VERSION);
      return 0;
    }
  }

  if (!o->scene && o->restore)
    return usage_error("--restore needs the scene file as well: a checkpoint "
                       "holds the state of a world, not the world");
  if (!o->scene) return usage_error("no scene file given");
  /* decidable from the command line, as --restore '' is */
  if (!*o->scene) return usage_error("the scene file name is empty");
  if (o->render_every_given && !o->render_dir)
    return usage_error("--render-every needs --render DIR");
  if (o->camera_pos_given != o->camera_look_given)
    return usage_error("--camera-pos and --camera-look-at go together");
  if (o->camera_pos_given && !ss_camera_valid(o->camera_pos, o->camera_look_at))
    return usage_error("--camera-pos and --camera-look-at must be distinct "
                       "points (the camera looks from one towards the other)");
  if ((o->camera_pos_given || o->camera_fov > 0 || o->camera_follow || o->color) &&
      !o->render_dir)
    return usage_error("--camera-* and --color need --render DIR");
  if (size_given && !o->render_dir && !o->rut_map)
    return usage_error("--size needs --render or --rut-map");
  if (o->rut_map && size_given &&
      (o->width < SS_RUT_MAP_MIN_WIDTH || o->height < SS_RUT_MAP_MIN_SIDE))
    return usage_error("--size %dx%d is too small for --rut-map: it must be "
                       "at least %d pixels wide and %d high", o->width,
                       o->height, SS_RUT_MAP_MIN_WIDTH, SS_RUT_MAP_MIN_SIDE);
  for (int i = 0; i < o->nremoval; i++)
    if (o->removal[i].step > o->steps)
      return usage_error("--remove %s: step %ld is after the last step "
                         "(--steps %ld%s)", o->removal[i].arg,
                         o->removal[i].step, o->steps,
                         steps_given ? "" : ", the default");

  for (int i = 0; i < o->nckpt; i++)
    if (o->ckpt[i].step > o->steps)
      return usage_error("--checkpoint %s: step %ld is after the last step "
                         "(--steps %ld%s)", o->ckpt[i].arg, o->ckpt[i].step,
                         o->steps, steps_given ? "" : ", the default");

  /* two outputs on one file would overwrite each other */
  return check_clashes(o);
}

/* ---------------------------------------------------------------------- */
/* checks made before the first step                                       */

/* An output must be writable as ss_atomic_open writes it: a new or
 * replaced file needs a folder that takes its temporary file (a folder is
 * refused), a stream (/dev/stdout, a FIFO) write permission.  open_output
 * opens it (the --csv rows are written as the run goes); check_output
 * only tries, for the outputs written later, and never opens a FIFO (its
 * reader would see the end of the output before it began). */
static ssStatus open_output(ssAtomicFile *f, const char *path, const char *flag, ssError *err)
{
  ssError e;
  ss_error_clear(&e);
  if (ss_atomic_open(f, path, &e) != SS_OK)
    return ss_error_set(err, SS_ERR_IO, path, 0, "%s: %s", flag, e.message);
  return SS_OK;
}

/* An output written in full but not committed: its buffered bytes go out
 * now, so that a write error (a full disk) is found before any output is
 * committed.  The commit reports it, with its reason. */
static ssStatus flush_output(ssAtomicFile *f, ssError *err)
{
  FILE *fp = (FILE *)f->fp;
  errno = 0;
  if (!f->error && fp && fflush(fp) != 0) f->error = errno ? errno : EIO;
  if (f->error || (fp && ferror(fp))) return ss_atomic_commit(f, err);
  return SS_OK;
}

/* An open output committed (put in place), and marked no longer open so
 * that a later failure does not abort it; SS_OK where it is not open */
static ssStatus commit_output(ssAtomicFile *f, int *open, ssError *err)
{
  if (!*open) return SS_OK;
  *open = 0;
  return ss_atomic_commit(f, err);
}

static ssStatus check_output(const char *path, const char *flag, ssError *err)
{
  ssError e;
  ss_error_clear(&e);
  if (ss_atomic_check(path, &e) != SS_OK)
    return ss_error_set(err, SS_ERR_IO, path, 0, "%s: %s", flag, e.message);
  return SS_OK;
}

/* mkdir -p: create dir and its missing parents. */
/* The folders make_dirs created, so that a run that fails before its
 * first frame takes them away again (rmdir: only while they are empty) */
static struct {
  char path[1024];
  size_t from; /* the first created folder is path[0, from) */
  int any;
} g_made;

static void unmake_dirs(void)
{
  if (!g_made.any) return;
  for (size_t k = strlen(g_made.path); k >= g_made.from; k--) {
    if (g_made.path[k] != '/' && g_made.path[k] != 0) continue;
    g_made.path[k] = 0;
    rmdir(g_made.path);
  }
  g_made.any = 0;
}

static ssStatus make_dirs(const char *dir, ssError *err)
{
  char path[1024];
  size_t n = strlen(dir);
  if (n >= sizeof path)
    return ss_error_set(err, SS_ERR_IO, dir, 0, "--render: path too long");
  memcpy(path, dir, n + 1);
  for (size_t k = 1; k <= n; k++) {
    if (path[k] != '/' && path[k] != 0) continue;
    char c = path[k];
    path[k] = 0;
    if (mkdir(path, 0777) == 0) {
      if (!g_made.any) {
        g_made.any = 1;
        g_made.from = k;
        memcpy(g_made.path, dir, n + 1);
      }
    } else if (errno != EEXIST) {
      int e = errno;
      return ss_error_set(err, SS_ERR_IO, path, 0,
                          "--render: cannot create directory: %s",
                          strerror(e));
    }
    path[k] = c;
  }
  struct stat st;
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
    return ss_error_set(err, SS_ERR_IO, dir, 0,
                        "--render: not a directory");
  return SS_OK;
}

/* The systems the scene has, for a message: "a, b, c" (truncated). */
static void list_systems(const ssModel *m, char *buf, size_t size)
{
  size_t used = 0;
  buf[0] = 0;
  for (int s = 0; s < m->nsys; s++) {
    int n = snprintf(buf + used, size - used, "%s'%s'", s ? ", " : "",
                     m->sys_name[s]);
    if (n < 0 || (size_t)n >= size - used) {
      if (size > 4) strcpy(buf + size - 5, " ...");
      return;
    }
    used += (size_t)n;
  }
}

static ssStatus check_removals(const Options *o, const ssModel *m,
                               ssError *err)
{
  for (int i = 0; i < o->nremoval; i++) {
    if (ss_model_find_sys(m, o->removal[i].name) >= 0) continue;
    if (m->nsys == 0)
      return ss_error_set(err, SS_ERR_NOTFOUND, o->scene, 0,
                          "--remove %s: no body or articulated system named "
                          "'%s'; the scene has none", o->removal[i].arg,
                          o->removal[i].name);
    char names[600];
    list_systems(m, names, sizeof names);
    return ss_error_set(err, SS_ERR_NOTFOUND, o->scene, 0,
                        "--remove %s: no body or articulated system named "
                        "'%s'; the scene has %s", o->removal[i].arg,
                        o->removal[i].name, names);
  }
  return SS_OK;
}

static int first_soil_bed(const ssModel *m)
{
  for (int h = 0; h < m->nhfield; h++)
    if (m->hfield_soil[h]) return h;
  return -1;
}

/* ---------------------------------------------------------------------- */
/* CSV                                                                     */

/* A header field, quoted when the name would break the CSV. */
static void csv_name(FILE *fp, const char *name, const char *suffix)
{
  if (!strpbrk(name, ",\"\r\n")) {
    fprintf(fp, ",%s%s", name, suffix);
    return;
  }
  fputs(",\"", fp);
  for (const char *c = name; *c; c++) {
    if (*c == '"') fputc('"', fp);
    fputc(*c, fp);
  }
  fprintf(fp, "%s\"", suffix);
}

static void csv_header(FILE *fp, const ssModel *m)
{
  fputs("step,time,soil_contacts,soil_contact_area,soil_normal_force,sweeps,newton,"
        "residual,converged",
        fp);
  for (int s = 0; s < m->nsys; s++) {
    csv_name(fp, m->sys_name[s], ".x");
    csv_name(fp, m->sys_name[s], ".y");
    csv_name(fp, m->sys_name[s], ".z");
  }
  fputc('\n', fp);
}

/* Numbers with round-trip precision; a removed system's fields stay empty. */
static void csv_row(FILE *fp, const ssModel *m, const ssData *d, long k)
{
  const ssStepStats *st = &d->stats;
  fprintf(fp, "%ld,%.17g,%d,%.17g,%.17g,%d,%d,%.17g,%d", k, d->time,
          st->soil_contacts, st->soil_contact_area, st->soil_normal_force,
          st->sweeps, st->newton, st->residual, st->converged);
  for (int s = 0; s < m->nsys; s++) {
    if (!d->sys_active[s] || m->sys_nbody[s] < 1) {
      fputs(",,,", fp);
      continue;
    }
    const double *p = d->body_xpos + 3 * m->sys_bodyadr[s];
    fprintf(fp, ",%.17g,%.17g,%.17g", p[0], p[1], p[2]);
  }
  fputc('\n', fp);
}

/* ---------------------------------------------------------------------- */
/* progress line                                                           */

static double now_seconds(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void format_duration(char *buf, size_t size, double sec)
{
  if (!(sec >= 0) || sec > 359999) {
    snprintf(buf, size, "--:--");
    return;
  }
  long t = (long)(sec + 0.5);
  if (t >= 3600)
    snprintf(buf, size, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
  else
    snprintf(buf, size, "%ld:%02ld", t / 60, t % 60);
}

static void progress_draw(Progress *p, long k, long n, double now)
{
  enum { BAR = 30 };
  double frac = n > 0 ? (double)k / (double)n : 1.0;
  double elapsed = now - p->start;
  char bar[BAR + 1], eta[32], rate[32];
  int fill = (int)(frac * BAR);
  for (int i = 0; i < BAR; i++) bar[i] = i < fill ? '#' : '.';
  bar[BAR] = 0;
  if (k > 0 && elapsed > 0) {
    double r = (double)k / elapsed;
    snprintf(rate, sizeof rate, "%.0f steps/s", r);
    format_duration(eta, sizeof eta, (double)(n - k) / r);
  } else {
    snprintf(rate, sizeof rate, "-- steps/s");
    snprintf(eta, sizeof eta, "--:--");
  }
  fprintf(stderr, "\r[%s] %3d%%  step %ld/%ld  %s  ETA %s\033[K", bar,
          (int)(frac * 100), k, n, rate, eta);
  fflush(stderr);
  p->drawn = 1;
  p->last = now;
}

static void progress_clear(Progress *p)
{
  if (!p->drawn) return;
  fputs("\r\033[K", stderr);
  fflush(stderr);
  p->drawn = 0;
}

/* ---------------------------------------------------------------------- */
/* the run                                                                 */

static void on_signal(int sig) { g_signal = sig; }

static void catch_signals(void)
{
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
  sigaction(SIGHUP, &sa, NULL);
}

static ssStatus render_step(ssRenderer *r, const Options *o, const ssModel *m,
                            const ssData *d, long k, long *nframes,
                            ssError *err)
{
  char path[2048];
  int n = snprintf(path, sizeof path, "%s%sframe_%06ld.png", o->render_dir,
                   dir_sep(o->render_dir), k);
  if (n < 0 || (size_t)n >= sizeof path)
    return ss_error_set(err, SS_ERR_IO, o->render_dir, 0,
                        "--render: path too long");
  ssStatus st = ss_render_frame(r, m, d, path, err);
  if (st == SS_OK) (*nframes)++;
  return st;
}

/* Removals scheduled for step k. */
static ssStatus apply_removals(const Options *o, const ssModel *m, ssData *d,
                               long k, ssError *err)
{
  for (int i = 0; i < o->nremoval; i++)
    if (o->removal[i].step == k &&
        ss_remove(m, d, o->removal[i].name, err) != SS_OK) {
      if (!err->file[0])
        snprintf(err->file, sizeof err->file, "%s", o->scene);
      return err->code;
    }
  return SS_OK;
}

/* Checkpoints scheduled for step k, written after its removals: the state
 * step k + 1 starts from. */
static ssStatus write_checkpoints(const Options *o, const ssModel *m,
                                  const ssData *d, long k, int *nwritten,
                                  ssError *err)
{
  for (int i = 0; i < o->nckpt; i++) {
    if (o->ckpt[i].step != k) continue;
    if (ss_checkpoint_save(m, d, o->ckpt[i].path, err) != SS_OK) return err->code;
    (*nwritten)++;
  }
  return SS_OK;
}

/* --restore: the checkpoint's solver configuration becomes the world's
 * (it is part of the saved world), then its state replaces the scene's. */
static ssStatus restore(const Options *o, ssModel *m, ssData *d,
                        ssCheckpointInfo *info, ssError *err)
{
  ssStatus st = ss_checkpoint_info(o->restore, info, err);
  if (st != SS_OK) return st;
  ss_option_copy_solver(&m->opt, &info->opt);
  return ss_checkpoint_load(m, d, o->restore, err);
}

/* --solver-tolerance, --max-sweeps, --warm-start over the scene's (or the
 * checkpoint's) <contact_solver>. */
static void apply_solver_overrides(const Options *o, ssModel *m)
{
  if (o->solver_tolerance > 0) m->opt.solver_tolerance = o->solver_tolerance;
  if (o->max_sweeps > 0) m->opt.solver_max_sweeps = (int)o->max_sweeps;
  if (o->warm_start >= 0) m->opt.terrain_warm_start = o->warm_start;
}

/* Whether an output is the pipe or file standard output writes to
 * (--csv /dev/stdout | ...): the summary then goes to standard error, out
 * of the data.  A terminal or /dev/null keeps it on standard output. */
static int output_is_stdout(const Options *o)
{
  struct stat so, st;
  if (fstat(STDOUT_FILENO, &so) != 0 || S_ISCHR(so.st_mode)) return 0;
  const char *path[3] = {o->export_path, o->csv_path, o->rut_map};
  for (int i = 0; i < 3 + o->nckpt; i++) {
    const char *p = i < 3 ? path[i] : o->ckpt[i - 3].path;
    if (p && stat(p, &st) == 0 && st.st_dev == so.st_dev &&
        st.st_ino == so.st_ino)
      return 1;
  }
  return 0;
}

static void print_summary(FILE *out, const Options *o, const ssModel *m,
                          const ssData *d, long steps, double wall,
                          long nframes, long unconverged,
                          const ssCheckpointInfo *restored)
{
  double sim = (double)steps * m->opt.timestep;
  fprintf(out, "scene       %s\n", o->scene);
  if (restored)
    fprintf(out, "restored    %s (step %ld, t = %.6g s)\n", o->restore,
            restored->step, restored->time);
  fprintf(out, "steps       %ld (dt %g s)\n", steps, m->opt.timestep);
  double gap = d->time - sim;
  if (gap > 0.5 * m->opt.timestep || gap < -0.5 * m->opt.timestep)
    fprintf(out, "simulated   %.6g s (scene time now %.6g s)\n", sim, d->time);
  else
    fprintf(out, "simulated   %.6g s\n", sim);
  if (wall > 0 && steps > 0)
    fprintf(out, "wall time   %.3f s (real-time factor %.3g)\n", wall,
            sim / wall);
  else
    fprintf(out, "wall time   %.3f s\n", wall);
  if (steps > 0) {
    fprintf(out, "sweeps      %d", d->stats.sweeps);
    int newton = d->stats.newton - d->stats.creep, creep = d->stats.creep;
    if (newton > 0)
      fprintf(out, " after %d Newton iteration%s", newton, newton == 1 ? "" : "s");
    if (creep > 0)
      fprintf(out, "%s %d creeping pass%s", newton > 0 ? " and" : " after", creep,
              creep == 1 ? "" : "es");
    fprintf(out, " (last step)");
    if (unconverged)
      fprintf(out, "; %ld step%s stopped at the sweep cap", unconverged,
              unconverged == 1 ? "" : "s");
    fputc('\n', out);
  }
  if (o->export_path) fprintf(out, "export      %s\n", o->export_path);
  if (o->csv_path) fprintf(out, "csv         %s\n", o->csv_path);
  if (o->render_dir)
    fprintf(out, "frames      %s%sframe_*.png (%ld)\n", o->render_dir,
            dir_sep(o->render_dir), nframes);
  if (o->rut_map) fprintf(out, "rut map     %s\n", o->rut_map);
  for (int i = 0; i < o->nckpt; i++)
    fprintf(out, "checkpoint  %s (after step %ld)\n", o->ckpt[i].path,
            o->ckpt[i].step);
}

static int run(const Options *o)
{
  ssError err;
  ssModel *m = NULL;
  ssData *d = NULL;
  ssRenderer *r = NULL;
  ssAtomicFile csv, rut, exp;
  int csv_open = 0, rut_open = 0, exp_open = 0, status = EXIT_RUN_FAILED;
  long nframes = 0, unconverged = 0, done = 0;
  int nckpt = 0;
  ssCheckpointInfo restored;
  double t0, wall;
  ssRenderOptions ropt = ss_render_options_default();
  Progress prog;
  memset(&prog, 0, sizeof prog);
  memset(&csv, 0, sizeof csv);
  memset(&rut, 0, sizeof rut);
  memset(&exp, 0, sizeof exp);
  ss_error_clear(&err);

  /* load and validate everything before the first step */
  if (ss_scene_load(o->scene, &m, &d, &err) != SS_OK) {
    if (!err.file[0]) snprintf(err.file, sizeof err.file, "%s", o->scene);
    goto fail;
  }
  if (check_removals(o, m, &err) != SS_OK) goto fail;
  /* the solver configuration: the scene's, or the checkpoint's when
   * restoring, then the command line's overrides */
  if (o->restore && restore(o, m, d, &restored, &err) != SS_OK) goto fail;
  apply_solver_overrides(o, m);
  /* the frames' folder first: another output may lie in it (--render D
   * --checkpoint D/k@5); made before anything is written, taken away
   * again on any failure before the first frame (unmake_dirs) */
  if (o->render_dir) {
    /* the first frame's name, which every run writes: a made-up probe
     * name refused a folder that held a folder of that name, and named a
     * file the run never writes */
    char probe[2048];
    snprintf(probe, sizeof probe, "%s%sframe_%06d.png", o->render_dir,
             dir_sep(o->render_dir), 0);
    if (make_dirs(o->render_dir, &err) != SS_OK ||
        check_output(probe, "--render", &err) != SS_OK)
      goto fail;
  }
  for (int i = 0; i < o->nckpt; i++)
    if (check_output(o->ckpt[i].path, "--checkpoint", &err) != SS_OK) goto fail;
  /* the step counter's limit, which ss_step refuses to pass: said before
   * the first step rather than after the steps that still fit */
  if (o->steps > LONG_MAX - d->step) {
    ss_error_set(&err, SS_ERR_VALUE, o->restore ? o->restore : o->scene, 0,
                 "--steps %ld: the world starts at step %ld (its clock) and "
                 "the step counter stops at %ld", o->steps, d->step, LONG_MAX);
    goto fail;
  }
  if (o->rut_map && first_soil_bed(m) < 0) {
    ss_error_set(&err, SS_ERR_VALUE, o->scene, 0,
                 "--rut-map: the scene has no soil bed");
    goto fail;
  }
  if (o->export_path && check_output(o->export_path, "--export", &err))
    goto fail;
  if (o->rut_map && check_output(o->rut_map, "--rut-map", &err)) goto fail;

  if (o->width > 0) {
    ropt.width = o->width;
    ropt.height = o->height;
  }
  /* what the rut map needs but the soil's values (its label font, found
   * only at the end of the run otherwise) */
  if (o->rut_map && ss_render_rut_map_check(m, -1, ropt.width, ropt.height, o->rut_map,
                                            &err) != SS_OK)
    goto fail;
  /* a camera from the command line replaces the scene's <camera> */
  if (o->camera_pos_given) {
    ropt.camera_given = 1;
    memcpy(ropt.camera_pos, o->camera_pos, sizeof ropt.camera_pos);
    memcpy(ropt.camera_look_at, o->camera_look_at, sizeof ropt.camera_look_at);
    ropt.camera_fov_deg = o->camera_fov > 0 ? o->camera_fov : 45;
    if (o->camera_follow)
      snprintf(ropt.camera_follow, sizeof ropt.camera_follow, "%s", o->camera_follow);
  } else if (o->camera_fov > 0 || o->camera_follow) {
    /* adjust the scene's camera (or the automatic one) */
    if (m->camera_given) {
      ropt.camera_given = 1;
      memcpy(ropt.camera_pos, m->camera_pos, sizeof ropt.camera_pos);
      memcpy(ropt.camera_look_at, m->camera_look_at, sizeof ropt.camera_look_at);
      ropt.camera_fov_deg = o->camera_fov > 0 ? o->camera_fov : m->camera_fov_deg;
      snprintf(ropt.camera_follow, sizeof ropt.camera_follow, "%s",
               o->camera_follow ? o->camera_follow : m->camera_follow);
    } else if (o->camera_follow) {
      ss_error_set(&err, SS_ERR_VALUE, o->scene, 0,
                   "--camera-follow needs a camera: give --camera-pos and "
                   "--camera-look-at, or a <camera> in the scene");
      goto fail;
    } else {
      /* the automatic overview, seen through this field of view */
      ropt.camera_fov_deg = o->camera_fov;
    }
  }
  /* a name the scene does not hold is the option's error, said with the
   * scene it was looked for in (the renderer's own message names neither) */
  if (o->camera_follow) {
    int s = ss_model_find_sys(m, o->camera_follow);
    if (s < 0 || m->sys_nbody[s] < 1) {
      ss_error_set(&err, SS_ERR_NOTFOUND, o->scene, 0,
                   "--camera-follow '%s': the scene has no body or articulated "
                   "system of that name", o->camera_follow);
      goto fail;
    }
  }
  if (o->color) ropt.color_mode = o->color - 1;
  if (o->render_dir) {
    r = ss_render_new(m, &ropt, &err);
    if (!r) {
      if (err.code == SS_OK)
        ss_error_set(&err, SS_ERR_UNSUPPORTED, "", 0,
                     "--render: the renderer could not start");
      goto fail;
    }
  }
  if (o->csv_path) {
    /* opened at once, with the other outputs' tests and messages */
    if (open_output(&csv, o->csv_path, "--csv", &err) != SS_OK) goto fail;
    csv_open = 1;
    csv_header((FILE *)csv.fp, m);
  }

  prog.on = !o->quiet && isatty(STDERR_FILENO) &&
            !(getenv("CI") && *getenv("CI"));
  catch_signals();
  ss_forward(m, d);
  t0 = now_seconds();
  prog.start = prog.last = t0;

  /* step k's outputs are recorded, then the removals scheduled for k apply;
   * k counts this run's steps (a scene may start at a later time) */
  for (long k = 0; k <= o->steps; k++) {
    if (g_signal) break;
    if (k > 0) {
      if (ss_step(m, d, &err) != SS_OK) {
        if (!err.file[0])
          snprintf(err.file, sizeof err.file, "%s", o->scene);
        goto fail;
      }
      ss_forward(m, d);
      done = k;
      if (!d->stats.converged) unconverged++;
      if (csv_open) csv_row((FILE *)csv.fp, m, d, k);
    }
    if (r && (k % o->render_every == 0 || k == o->steps) &&
        render_step(r, o, m, d, k, &nframes, &err) != SS_OK)
      goto fail;
    if (apply_removals(o, m, d, k, &err) != SS_OK) goto fail;
    if (write_checkpoints(o, m, d, k, &nckpt, &err) != SS_OK) goto fail;
    if (prog.on) {
      double now = now_seconds();
      if (now - prog.last >= 0.1 || k == o->steps)
        progress_draw(&prog, k, o->steps, now);
    }
  }
  wall = now_seconds() - t0;
  if (g_signal) {
    progress_clear(&prog);
    /* what is written as the run goes stays: say what that is */
    char ck[64] = "", fr[64] = "";
    if (nckpt)
      snprintf(ck, sizeof ck, "the %d checkpoint%s of earlier steps", nckpt,
               nckpt == 1 ? "" : "s");
    if (nframes)
      snprintf(fr, sizeof fr, "the %ld frame%s drawn so far", nframes,
               nframes == 1 ? "" : "s");
    if (nckpt || nframes)
      fprintf(stderr, "soilsim: interrupted after step %ld; only %s%s%s written\n", done,
              ck, nckpt && nframes ? " and " : "", fr);
    else
      fprintf(stderr, "soilsim: interrupted after step %ld; no output files "
              "written\n", done);
    g_interrupted = 1;
    goto cleanup;
  }
  progress_clear(&prog);

  /* outputs of the final state: all of them written and flushed before
   * any is committed, so that a failure leaves none of them (the rut map
   * stayed when the export then failed); the CSV is committed last */
  if (o->rut_map) {
    if (open_output(&rut, o->rut_map, "--rut-map", &err) != SS_OK) goto fail;
    rut_open = 1;
    if (ss_render_rut_map_to(m, d, -1, 1, ropt.width, ropt.height, &rut,
                             &err) != SS_OK)
      goto fail;
    /* a stream (a FIFO's reader waits for its end) is finished at once:
     * it has nothing to roll back */
    if (rut.direct && commit_output(&rut, &rut_open, &err) != SS_OK) goto fail;
  }
  if (o->export_path) {
    if (open_output(&exp, o->export_path, "--export", &err) != SS_OK)
      goto fail;
    exp_open = 1;
    if (ss_scene_export_to(m, d, &exp, &err) != SS_OK) goto fail;
    if (exp.direct && commit_output(&exp, &exp_open, &err) != SS_OK) goto fail;
  }
  if ((rut_open && flush_output(&rut, &err) != SS_OK) ||
      (exp_open && flush_output(&exp, &err) != SS_OK) ||
      (csv_open && flush_output(&csv, &err) != SS_OK))
    goto fail;
  if (commit_output(&rut, &rut_open, &err) != SS_OK ||
      commit_output(&exp, &exp_open, &err) != SS_OK ||
      commit_output(&csv, &csv_open, &err) != SS_OK)
    goto fail;
  if (!o->quiet) {
    /* a summary that cannot be written (standard output on a full disk or
     * a closed pipe) fails the run, as any output would; the files are
     * complete by now, and the message says so */
    FILE *out = output_is_stdout(o) ? stderr : stdout;
    print_summary(out, o, m, d, done, wall, nframes, unconverged,
                  o->restore ? &restored : NULL);
    errno = 0;
    if (fflush(out) != 0 || ferror(out)) {
      ss_error_set(&err, SS_ERR_IO, NULL, 0,
                   "the summary could not be written to standard %s (%s); "
                   "the output files are complete", out == stdout ? "output" : "error",
                   errno ? strerror(errno) : "write error");
      report(&err);
      goto cleanup;
    }
  }
  status = 0;
  goto cleanup;

fail:
  progress_clear(&prog);
  report(&err);
  status = EXIT_RUN_FAILED;
  unmake_dirs();
cleanup:
  if (csv_open) ss_atomic_abort(&csv);
  if (rut_open) ss_atomic_abort(&rut);
  if (exp_open) ss_atomic_abort(&exp);
  ss_render_free(r);
  ss_data_free(d);
  ss_model_free(m);
  return status;
}

int main(int argc, char **argv)
{
  Options o;
  int status = parse_args(argc, argv, &o);
  if (status < 0) status = run(&o);
  options_free(&o);
  if (g_interrupted) {
    /* let the caller see how we ended (a shell loop stops on Ctrl-C) */
    int sig = g_signal;
    signal(sig, SIG_DFL);
    raise(sig);
  }
  return status;
}
