/* step.c -- one time step, stage by stage, each timed. */
#include "soilsim.h"
#include "articulated.h"
#include "dynamics.h"
#include "solver.h"
#include "terrain.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

ssStatus ss_step(const ssModel *m, ssData *d, ssError *err)
{
  if (d->in_step)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0, "ss_step called re-entrantly");
  /* the step counter's limit: a <clock> or a checkpoint may start it
   * anywhere in [0, LONG_MAX], and one more step would overflow it (its
   * export or checkpoint could then not be read back) */
  if (d->step == LONG_MAX)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "the step counter is at its maximum (%ld steps); "
                        "nothing was stepped", d->step);
  /* the options and each bed's material as ss_model_validate checks them:
   * a program may edit m->opt and m->hfield_soilmat between steps, and
   * with an invalid one nothing is simulated (DESIGN 2.5: a time step of 0
   * or NaN, a tolerance of 2, a material with negative damping); a few
   * comparisons per step and bed */
  ssError invalid;
  ssStatus st = ss_model_validate(m, &invalid);
  if (st)
    return ss_error_set(err, st, NULL, 0, "step %ld (from t = %.6g s): %s; "
                        "nothing was stepped", d->step + 1, d->time, invalid.message);
  /* the state a step starts from: a caller may have written it between
   * steps (or a checkpoint restored it), and none of it is used before
   * it has passed the test that every step's result passes */
  char why[300];
  if (!ss_dyn_check_state(m, d, why, sizeof why))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "step %ld (t = %.6g s): %s before the step (set between "
                        "steps or restored); nothing was stepped", d->step + 1,
                        d->time + m->opt.timestep, why);
  /* the time (finite, as just checked) stays finite after the step */
  if (!isfinite(d->time + m->opt.timestep))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "step %ld: the time %.17g s plus the time step %g s is "
                        "not finite; nothing was stepped", d->step + 1, d->time,
                        m->opt.timestep);
  /* keep the coordinates and velocities so a failed step leaves d where it
   * was; the soil state and the warm-start cache are written only once
   * every check has passed */
  size_t ns = (size_t)m->nq + (size_t)m->nv;
  double stack[128], *saved = ns <= 128 ? stack : malloc(ns * sizeof(double));
  if (!saved) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  if (m->nq) memcpy(saved, d->qpos, (size_t)m->nq * sizeof(double));
  if (m->nv) memcpy(saved + m->nq, d->qvel, (size_t)m->nv * sizeof(double));
  /* a quaternion written between steps made unit (after the copy: a step
   * that fails leaves it as it was written) */
  ss_dyn_unit_quats(m, d);
  double closure0 = d->closure_error;
  ssStepStats stats0 = d->stats;
  d->in_step = 1;
  double *t = d->stats.time_stage, t0 = now(), t1;

  /* poses of bodies and colliders from qpos (an articulated system's
   * stand where the last step left them for this qpos) */
  ss_forward_step(m, d);
  t1 = now(); t[0] = t1 - t0; t0 = t1;

  /* velocities under gravity, external loads, force elements and loop
   * closures (the velocities before them kept for restitution) */
  if (m->nv) memcpy(d->qvel_start, d->qvel, (size_t)m->nv * sizeof(double));
  if ((st = ss_dyn_free_velocity(m, d, err))) goto fail;
  t1 = now(); t[1] = t1 - t0; t0 = t1;

  /* soil quadrature points, rigid contacts and joint rows, with their
   * responses */
  ss_solver_pow_tables(m, d);
  if ((st = ss_terrain_contacts(m, d, err))) goto fail;
  if ((st = ss_art_rows(m, d, err))) goto fail;
  if ((st = ss_terrain_reserve(d, err))) goto fail;
  t1 = now(); t[2] = t1 - t0; t0 = t1;

  /* implicit contact impulses at the end-of-step velocity */
  if ((st = ss_solver_solve(m, d, err))) goto fail;
  t1 = now(); t[3] = t1 - t0; t0 = t1;

  int vel, bad = ss_dyn_check_finite(m, d, &vel);
  if (bad >= 0) {
    st = ss_error_set(err, SS_ERR_NUMERIC, NULL, 0,
                      "step %ld (t = %.6g s): the velocity of '%s' became "
                      "non-finite or absurd; the time step may be too large "
                      "for the stiffness in the scene",
                      d->step + 1, d->time + m->opt.timestep, m->sys_name[bad]);
    goto fail;
  }

  /* positions from the new velocities and the push out of penetrations,
   * which moves them and leaves the velocities as they are; loop-closure
   * drift removed */
  int push = ss_solver_push(m, d);
  if (push < 0) {
    st = ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    goto fail;
  }
  /* a push is a velocity too, under the same limit (its contacts' targets
   * are bounded, ss_solver_push; a light body between them is not) */
  for (int s = 0; push && s < m->nsys; s++)
    if (d->sys_active[s] && !ss_all_within(d->qvel_push + m->sys_vadr[s], m->sys_nv[s], SS_SPEED_MAX)) {
      st = ss_error_set(err, SS_ERR_NUMERIC, NULL, 0,
                        "step %ld (t = %.6g s): the push of '%s' out of its "
                        "penetration became non-finite or absurd (above %g m/s "
                        "or rad/s); the penetration is too deep for rigid_erp "
                        "%g to remove in one step", d->step + 1,
                        d->time + m->opt.timestep, m->sys_name[s], SS_SPEED_MAX,
                        m->opt.rigid_erp);
      goto fail;
    }
  d->closure_error = 0;
  if (push)
    for (int k = 0; k < m->nv; k++) {
      double u = d->qvel[k];
      d->qvel[k] += d->qvel_push[k];
      d->qvel_push[k] = u;
    }
  ss_dyn_integrate(m, d);
  if (push) memcpy(d->qvel, d->qvel_push, (size_t)m->nv * sizeof(double));
  ss_forward_step(m, d);
  t1 = now(); t[5] = t1 - t0; t0 = t1;

  bad = ss_dyn_check_finite(m, d, &vel);
  if (bad >= 0) {
    st = ss_error_set(err, SS_ERR_NUMERIC, NULL, 0,
                      "step %ld (t = %.6g s): the %s of '%s' became "
                      "non-finite%s", d->step + 1, d->time + m->opt.timestep,
                      vel ? "velocity" : "position", m->sys_name[bad],
                      vel ? " or absurd" : "");
    goto fail;
  }

  /* the step stands: this step's tractions seed the next one, and the soil
   * takes its sinkage, permanent ruts and shear history (neither depends
   * on the new positions) */
  if ((st = ss_solver_store_warm(m, d, err))) goto fail;
  ss_terrain_update(m, d);
  t1 = now(); t[4] = t1 - t0;
  d->time += m->opt.timestep;
  d->step++;
  d->in_step = 0;
  if (saved != stack) free(saved);
  return SS_OK;

fail:
  if (m->nq) memcpy(d->qpos, saved, (size_t)m->nq * sizeof(double));
  if (m->nv) memcpy(d->qvel, saved + m->nq, (size_t)m->nv * sizeof(double));
  d->closure_error = closure0;
  d->stats = stats0;
  ss_forward(m, d);
  if (saved != stack) free(saved);
  d->in_step = 0;
  return st;
}
