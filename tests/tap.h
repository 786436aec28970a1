/* tap.h -- a tiny TAP producer for the test programs (no framework).
 * ok(cond, fmt...) prints "ok N - ..." or "not ok N - ..."; close_enough()
 * checks |a - b| <= tol and prints both values on failure; done_testing()
 * prints the plan and returns the exit status. */
#ifndef SS_TAP_H
#define SS_TAP_H
#include <math.h>
#include <stdarg.h>
#include <stdio.h>

static int tap_n, tap_fail;

static inline int ok(int cond, const char *fmt, ...)
{
  va_list ap;
  va_start(ap, fmt);
  printf("%s %d - ", cond ? "ok" : "not ok", ++tap_n);
  vprintf(fmt, ap);
  printf("\n");
  va_end(ap);
  if (!cond) tap_fail++;
  fflush(stdout);
  return cond;
}

static inline int close_enough(double got, double want, double tol, const char *what)
{
  int c = isfinite(got) && fabs(got - want) <= tol;
  ok(c, "%s: got %.9g, want %.9g (tol %.3g)", what, got, want, tol);
  return c;
}

static inline void diag(const char *fmt, ...)
{
  va_list ap;
  va_start(ap, fmt);
  printf("# ");
  vprintf(fmt, ap);
  printf("\n");
  va_end(ap);
}

static inline int done_testing(void)
{
  printf("1..%d\n", tap_n);
  return tap_fail ? 1 : 0;
}
#endif
