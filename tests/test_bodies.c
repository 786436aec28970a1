/* test_bodies.c -- contacts between bodies (DESIGN 3: rigid contacts
 * between bodies, a Coulomb cone solved in the sweeps): a body on a static
 * one, a stack, a log across a table, a crate across a log, crossed logs,
 * a plank and a log across a post, two balls meeting in free space, sliding on a
 * static body, a link against a static body.  Numbers from closed forms:
 * rest heights from the shapes' sizes, momentum and restitution for the
 * balls, mu g for sliding.  Before these contacts existed every body
 * passed through every other. */
#include "soilsim.h"
#include "tap.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* a world from a scene text (the rest of the scene's defaults) */
static int load(const char *xml, ssModel **m, ssData **d)
{
  ssError e;
  *m = NULL;
  *d = NULL;
  if (ss_scene_load_buffer(xml, strlen(xml), "bodies.xml", m, d, &e) != SS_OK) {
    diag("load failed: %s", e.message);
    return 0;
  }
  return 1;
}

static int steps(const ssModel *m, ssData *d, int n)
{
  ssError e;
  for (int k = 0; k < n; k++)
    if (ss_step(m, d, &e) != SS_OK) {
      diag("step %ld failed: %s", d->step + 1, e.message);
      return 0;
    }
  return 1;
}

static void drop(ssModel *m, ssData *d)
{
  ss_data_free(d);
  ss_model_free(m);
}

/* the largest speed of the free body whose velocities start at v */
static double speed(const double *v)
{
  double s = 0;
  for (int k = 0; k < 6; k++) s = fmax(s, fabs(v[k]));
  return s;
}

/* A box dropped onto a static table rests on it: its centre half its
 * height above the table's top (0.5 + 0.05 m).  It fell through the table
 * onto the ground (z = 0.05).  Tolerance: the solve stops the contacts at
 * its 1e-9 and the push leaves a penetration of 0.8^k of what the landing
 * made; after 2 s both are far below 1e-6 m. */
static void test_on_static(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<box name=\"table\" body_type=\"static\"><dim x=\"1\" y=\"1\" z=\"0.5\"/>"
      "<state pos=\"0 0 0.25\"/></box>"
      "<box name=\"b\" mass=\"2\"><dim x=\"0.2\" y=\"0.3\" z=\"0.1\"/>"
      "<state pos=\"0.1 -0.2 0.8\"/></box></objects></raisim>";
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "box on a static table: loads");
    return;
  }
  int sys = ss_model_find_sys(m, "b");
  int good = sys >= 0 && steps(m, d, 2000);
  const double *q = d->qpos + m->sys_qadr[sys], *v = d->qvel + m->sys_vadr[sys];
  ok(good && fabs(q[2] - 0.55) <= 1e-6 && speed(v) <= 1e-6,
     "a box dropped on a static table rests on it: z %.9f m (0.55), speed %.3g", q[2], speed(v));
  drop(m, d);
}

/* Two boxes stacked on the ground: the lower one (5 kg, 0.2 m high)
 * rests at z = 0.1, the upper one (1 kg, 0.1 m) dropped onto it at 0.25.
 * The upper one fell through the lower one to the ground. */
static void test_stack(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<box name=\"low\" mass=\"5\"><dim x=\"0.4\" y=\"0.4\" z=\"0.2\"/>"
      "<state pos=\"0 0 0.1\"/></box>"
      "<box name=\"up\" mass=\"1\"><dim x=\"0.2\" y=\"0.2\" z=\"0.1\"/>"
      "<state pos=\"0.05 0.02 0.4\" quat=\"0.9961947 0 0 0.0871557\"/></box>"
      "</objects></raisim>";
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "a stack of two boxes: loads");
    return;
  }
  int lo = ss_model_find_sys(m, "low"), up = ss_model_find_sys(m, "up");
  int good = lo >= 0 && up >= 0 && steps(m, d, 3000);
  const double *ql = d->qpos + m->sys_qadr[lo], *qu = d->qpos + m->sys_qadr[up];
  double sl = speed(d->qvel + m->sys_vadr[lo]), su = speed(d->qvel + m->sys_vadr[up]);
  ok(good && fabs(ql[2] - 0.1) <= 1e-6 && fabs(qu[2] - 0.25) <= 1e-6 && sl <= 1e-6 &&
         su <= 1e-6,
     "a box dropped on a box on the ground: both rest, at z %.9f (0.1) and %.9f (0.25) m, "
     "speeds %.3g and %.3g", ql[2], qu[2], sl, su);
  drop(m, d);
}

/* Two equal balls in free space (no gravity, no ground), one at 1 m/s
 * along the line of centres onto the other at rest.  Momentum is kept
 * (the pair's impulses are equal and opposite) and the restitution e
 * sets the parting speed: with e = 1 they exchange velocities, with e = 0
 * they go on together at 0.5 m/s.  Tolerance: the sweeps' 1e-9 of the
 * impulse (1 N s). */
static void balls(double e, double want_a, double want_b)
{
  char xml[1024];
  snprintf(xml, sizeof xml,
           "<raisim version=\"1.0\"><timeStep value=\"0.001\"/>"
           "<gravity value=\"0 0 0\"/><objects>"
           "<sphere name=\"a\" mass=\"1\"><dim radius=\"0.1\"/>"
           "<state pos=\"-0.5 0 1\" lin_vel=\"1 0 0\"/></sphere>"
           "<sphere name=\"b\" mass=\"1\"><dim radius=\"0.1\"/>"
           "<state pos=\"0 0 1\"/></sphere></objects>"
           "<material><default friction=\"0.5\" restitution=\"%g\" "
           "restitution_threshold=\"0\"/></material></raisim>",
           e);
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "two balls, restitution %g: loads", e);
    return;
  }
  int a = ss_model_find_sys(m, "a"), b = ss_model_find_sys(m, "b");
  int good = a >= 0 && b >= 0 && steps(m, d, 1000);
  const double *va = d->qvel + m->sys_vadr[a], *vb = d->qvel + m->sys_vadr[b];
  double p = va[0] + vb[0], side = fabs(va[1]) + fabs(va[2]) + fabs(vb[1]) + fabs(vb[2]);
  ok(good && fabs(p - 1) <= 1e-9 && fabs(va[0] - want_a) <= 1e-9 &&
         fabs(vb[0] - want_b) <= 1e-9 && side <= 1e-12,
     "two equal balls meeting at 1 m/s, restitution %g: %.12f and %.12f m/s after (%g and "
     "%g), momentum %.12f (1)", e, va[0], vb[0], want_a, want_b, p);
  /* they never pass through each other */
  const double *xa = d->qpos + m->sys_qadr[a], *xb = d->qpos + m->sys_qadr[b];
  ok(good && xb[0] - xa[0] >= 0.2 - 1e-6,
     "  and stay apart: centres %.9f m apart (at least 0.2)", xb[0] - xa[0]);
  drop(m, d);
}

static void test_balls(void)
{
  balls(1, 0, 1);
  balls(0, 0.5, 0.5);
}

/* A box sliding at 1 m/s on a static table with friction 0.5 decelerates
 * at mu g: its speed after 0.1 s is 1 - 0.5 g 0.1.  Tolerance: the
 * sweeps' 1e-9 of the impulse over 100 steps. */
static void test_slide(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><gravity value=\"0 0 -9.81\"/>"
      "<objects><box name=\"table\" body_type=\"static\"><dim x=\"4\" y=\"1\" z=\"0.5\"/>"
      "<state pos=\"0 0 0.25\"/></box>"
      "<box name=\"b\" mass=\"2\"><dim x=\"0.2\" y=\"0.2\" z=\"0.1\"/>"
      "<state pos=\"-1 0 0.55\" lin_vel=\"1 0 0\"/></box></objects>"
      "<material><default friction=\"0.5\" restitution=\"0\" restitution_threshold=\"0\"/>"
      "</material></raisim>";
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "a box sliding on a static table: loads");
    return;
  }
  int sys = ss_model_find_sys(m, "b");
  int good = sys >= 0 && steps(m, d, 100);
  const double *v = d->qvel + m->sys_vadr[sys], *q = d->qpos + m->sys_qadr[sys];
  double want = 1 - 0.5 * 9.81 * 0.1;
  ok(good && fabs(v[0] - want) <= 1e-7 && fabs(q[2] - 0.55) <= 1e-9,
     "a box sliding on a static table at 1 m/s, friction 0.5: %.10f m/s after 0.1 s "
     "(1 - mu g t = %.10f), height %.10f m (0.55)", v[0], want, q[2]);
  drop(m, d);
}

/* Two bodies of a scene text dropped and settled for n steps: each
 * one's height against want[k] and its largest speed (tolerance as
 * test_on_static's), one ok each, what[k] naming its case */
static void two_rest_at(const char *xml, const char *name[2], const char *what[2],
                        const double want[2], int n)
{
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "%s: loads", what[0]);
    ok(0, "%s: loads", what[1]);
    return;
  }
  int sys[2] = {ss_model_find_sys(m, name[0]), ss_model_find_sys(m, name[1])};
  int good = sys[0] >= 0 && sys[1] >= 0 && steps(m, d, n);
  for (int k = 0; k < 2; k++) {
    double z = good ? d->qpos[m->sys_qadr[sys[k]] + 2] : NAN;
    double sp = good ? speed(d->qvel + m->sys_vadr[sys[k]]) : NAN;
    ok(good && fabs(z - want[k]) <= 1e-6 && sp <= 1e-6, "%s: z %.9f m (%g), speed %.3g",
       what[k], z, want[k], sp);
  }
  drop(m, d);
}

/* the same after 2 s, both at want */
static void two_rest(const char *xml, const char *name[2], const char *what[2], double want)
{
  two_rest_at(xml, name, what, (const double[2]){want, want}, 2000);
}

/* A log lying across something narrower than itself, and a crate lying
 * across a log: each rests on the crossings of the box's edges with the
 * log's side.  A 2 m log (r 0.1, 20 kg) dropped across a 1 m static table
 * (top at 0.4 m) rests with its axis at 0.5; a crate (0.3 x 0.3 x 0.2, 5
 * kg, turned 15 degrees about z) dropped across a static log (r 0.2,
 * axis at 0.2 m) rests at 0.5.  Both fell: the log through the table to
 * the ground (0.1), the crate into the log until its corners met it
 * (0.470).  Tolerance as test_on_static's. */
static void test_across_log(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<box name=\"table\" body_type=\"static\"><dim x=\"1\" y=\"1\" z=\"0.4\"/>"
      "<state pos=\"0 0 0.2\"/></box>"
      "<cylinder name=\"log\" mass=\"20\"><dim radius=\"0.1\" height=\"2\"/>"
      "<state pos=\"0.05 0 0.505\" quat=\"0.7071067811865476 -0.7071067811865476 0 0\"/>"
      "</cylinder>"
      "<cylinder name=\"static_log\" body_type=\"static\"><dim radius=\"0.2\" height=\"2\"/>"
      "<state pos=\"3 0 0.2\" quat=\"0.7071067811865476 -0.7071067811865476 0 0\"/>"
      "</cylinder>"
      "<box name=\"crate\" mass=\"5\"><dim x=\"0.3\" y=\"0.3\" z=\"0.2\"/>"
      "<state pos=\"3 0.1 0.505\" quat=\"0.9914448613738104 0 0 0.13052619222005157\"/></box>"
      "</objects></raisim>";
  const char *name[2] = {"log", "crate"};
  const char *what[2] = {"a 2 m log dropped across a 1 m static table rests on the table's edges",
                         "a crate dropped across a static log rests on it"};
  two_rest(xml, name, what, 0.5);
}

/* A log (r 0.1, 10 kg) dropped crosswise onto a static log (r 0.2, axis
 * at 0.2 m), centred over it, and a capsule the same onto another: each
 * rests where the axes cross, its axis at 0.2 + 0.2 + 0.1 = 0.5 m.  The
 * log fell into the lower log and on to the ground (0.1); the capsule's
 * middle point (towards the lower log's centre, which it crosses square)
 * held it before as well.  Tolerance as test_on_static's. */
static void test_crossed_logs(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<cylinder name=\"low\" body_type=\"static\"><dim radius=\"0.2\" height=\"2\"/>"
      "<state pos=\"0 0 0.2\" quat=\"0.7071067811865476 -0.7071067811865476 0 0\"/>"
      "</cylinder>"
      "<cylinder name=\"up\" mass=\"10\"><dim radius=\"0.1\" height=\"2\"/>"
      "<state pos=\"0 0.3 0.505\" quat=\"0.7071067811865476 0 0.7071067811865476 0\"/>"
      "</cylinder>"
      "<cylinder name=\"low2\" body_type=\"static\"><dim radius=\"0.2\" height=\"2\"/>"
      "<state pos=\"4 0 0.2\" quat=\"0.7071067811865476 -0.7071067811865476 0 0\"/>"
      "</cylinder>"
      "<capsule name=\"cap\" mass=\"10\"><dim radius=\"0.1\" height=\"1.5\"/>"
      "<state pos=\"4 -0.2 0.505\" quat=\"0.7071067811865476 0 0.7071067811865476 0\"/>"
      "</capsule></objects></raisim>";
  const char *name[2] = {"up", "cap"};
  const char *what[2] = {"a log dropped crosswise onto a static log rests on it",
                         "a capsule dropped crosswise onto a static log rests on it"};
  two_rest(xml, name, what, 0.5);
}

/* A plank (0.1 x 1.2 x 0.05 m, 5 kg) dropped across a static post (a
 * cylinder standing on its end, r 0.3 m, top at 0.5 m), turned 22.5
 * degrees so that none of the post's 8 rim points lies under it: it
 * rests on its two bottom edges over the cap, at 0.525 m, still.  It fell
 * into the post until it met the rim (with its edges taken only between
 * the caps: it sank, was pushed out below 2e-10 m of penetration, lost
 * the edges' contacts and fell again, 10 um hops every 1.5 s).
 * Tolerance as test_on_static's; still: the same height over the last
 * second to 1e-12 m. */
static void test_plank_on_post(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<cylinder name=\"post\" body_type=\"static\"><dim radius=\"0.3\" height=\"0.5\"/>"
      "<state pos=\"0 0 0.25\"/></cylinder>"
      "<box name=\"plank\" mass=\"5\"><dim x=\"0.1\" y=\"1.2\" z=\"0.05\"/>"
      "<state pos=\"0 0 0.53\" quat=\"0.9807852804032304 0 0 0.19509032201612825\"/></box>"
      "</objects></raisim>";
  ssModel *m;
  ssData *d;
  if (!load(xml, &m, &d)) {
    ok(0, "plank on a post: loads");
    return;
  }
  int pl = ss_model_find_sys(m, "plank");
  int good = pl >= 0 && steps(m, d, 2000);
  const double *q = good ? d->qpos + m->sys_qadr[pl] : NULL;
  double zlo = INFINITY, zhi = -INFINITY;
  for (int k = 0; good && k < 1000; k++) {
    good = steps(m, d, 1);
    zlo = fmin(zlo, q[2]);
    zhi = fmax(zhi, q[2]);
  }
  ok(good && fabs(zlo - 0.525) <= 1e-6 && zhi - zlo <= 1e-12,
     "a plank dropped across a post's top, turned off its rim points, rests on its bottom "
     "edges: z %.9f-%.9f m (0.525)", zlo, zhi);
  drop(m, d);
}

/* A log (r 0.05 m, 1.2 m long, 10 kg) dropped across the top of a static
 * post (r 0.3 m, top at 0.5 m), turned 22.5 degrees so that none of the
 * post's 8 rim points lies under it: it rests on the cap at 0.55 m; so
 * does a capsule the same on another post.  The log balanced a while on
 * what it found and then fell to the ground (0.05); the capsule's middle
 * point held it before as well.  Tolerance as test_on_static's. */
static void test_log_on_post(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<cylinder name=\"post\" body_type=\"static\"><dim radius=\"0.3\" height=\"0.5\"/>"
      "<state pos=\"0 0 0.25\"/></cylinder>"
      "<cylinder name=\"log\" mass=\"10\"><dim radius=\"0.05\" height=\"1.2\"/>"
      "<state pos=\"0 0 0.56\" quat=\"0.6935199226610738 -0.6935199226610738 "
      "0.13794968964147153 0.13794968964147153\"/></cylinder>"
      "<cylinder name=\"post2\" body_type=\"static\"><dim radius=\"0.3\" height=\"0.5\"/>"
      "<state pos=\"3 0 0.25\"/></cylinder>"
      "<capsule name=\"pole\" mass=\"10\"><dim radius=\"0.05\" height=\"1.2\"/>"
      "<state pos=\"3 0 0.56\" quat=\"0.6935199226610738 -0.6935199226610738 "
      "0.13794968964147153 0.13794968964147153\"/></capsule>"
      "</objects></raisim>";
  const char *name[2] = {"log", "pole"};
  const char *what[2] = {"a log dropped across a post's top, turned off its rim points, rests "
                         "on the cap",
                         "  and a capsule the same on another post"};
  two_rest_at(xml, name, what, (const double[2]){0.55, 0.55}, 3000);
}

int main(void)
{
  test_on_static();
  test_stack();
  test_across_log();
  test_crossed_logs();
  test_plank_on_post();
  test_log_on_post();
  test_balls();
  test_slide();
  return done_testing();
}
