/* sort_runs.h -- a natural merge sort for arrays that come in a few sorted
 * runs (the contacts of one collider, the points of a polygon), written
 * once for any element type.
 *
 * SS_SORT_RUNS(name, T, less) defines
 *
 *   static T *name(T *v, T *t, int n)
 *   static T *name_from(T *v, T *t, int n, int e0)
 *
 * which sort the n elements of v, with the scratch t of n elements, by
 * less(const T *a, const T *b) (a strict order), and return whichever of v
 * and t ends holding them (v when they were sorted already, or all but a
 * short tail: SS_SORT_RUNS_TAIL).  name_from is told that the first e0
 * elements are in order (a caller that saw them come; 0 or 1 when it does
 * not know), and scans the first run on from there.  The first pass finds
 * the runs -- non-decreasing, or strictly decreasing and then reversed in
 * place -- and each pass merges them pairwise, taking the left element on
 * ties: the sort is stable, so its result is the one stable order,
 * whatever the runs.  A pass keeps the ends of the runs it merged into
 * for the next one (SS_SORT_RUNS_MAX of them; those after are found by
 * scanning again), and the rest of a run the other one ran out before is
 * copied as a block.  Linear for input already sorted, a few passes for
 * a few runs; no allocation and no call through a pointer per comparison
 * (the element type and comparison are the caller's, inlined). */
#ifndef SS_SORT_RUNS_H
#define SS_SORT_RUNS_H

#include <string.h>

/* a first run followed by at most this many elements: those are inserted
 * into it in place (a binary search and a move each) instead of merged
 * through the scratch (every element copied): the joint rows after a
 * step's soil points, where one PD row's dof comes before another's */
#define SS_SORT_RUNS_TAIL 8

/* the run ends a pass keeps for the next (a stack array) */
#define SS_SORT_RUNS_MAX 32

/* name() is a convenience that a user of name_from alone leaves unused;
 * clang warns of an unused static inline function defined in a .c file */
#if defined(__GNUC__)
#define SS_SORT_RUNS_MAYBE_UNUSED __attribute__((unused))
#else
#define SS_SORT_RUNS_MAYBE_UNUSED
#endif

#define SS_SORT_RUNS(name, T, less)                                            \
  static int name##_run(T *v, int i, int n)                                    \
  {                                                                            \
    int j = i + 1;                                                             \
    if (j < n && less(&v[j], &v[i])) {                                         \
      while (j + 1 < n && less(&v[j + 1], &v[j])) j++;                         \
      for (int a = i, b = j; a < b; a++, b--) {                                \
        T tmp = v[a];                                                          \
        v[a] = v[b];                                                           \
        v[b] = tmp;                                                            \
      }                                                                        \
      j++;                                                                     \
    }                                                                          \
    while (j < n && !less(&v[j], &v[j - 1])) j++;                              \
    return j;                                                                  \
  }                                                                            \
  static T *name##_from(T *v, T *t, int n, int e0)                             \
  {                                                                            \
    if (e0 < 2) e0 = name##_run(v, 0, n);                                      \
    while (e0 < n && !less(&v[e0], &v[e0 - 1])) e0++;                          \
    if (e0 >= n) return v;                                                     \
    if (n - e0 <= SS_SORT_RUNS_TAIL) {                                         \
      /* a sorted run and a short tail: each tail element inserted in      */ \
      /* place after the last element not greater than it (stable)         */ \
      for (int k = e0; k < n; k++) {                                           \
        T x = v[k];                                                            \
        int lo = 0, hi = k;                                                    \
        while (lo < hi) {                                                      \
          int mid = lo + (hi - lo) / 2;                                        \
          if (less(&x, &v[mid])) hi = mid;                                     \
          else lo = mid + 1;                                                   \
        }                                                                      \
        memmove(v + lo + 1, v + lo, (size_t)(k - lo) * sizeof *v);            \
        v[lo] = x;                                                             \
      }                                                                        \
      return v;                                                                \
    }                                                                          \
    /* the ends of the runs a pass merges: the first run's, then those     */ \
    /* the last pass kept (known of them), then found by scanning          */ \
    int run_end[SS_SORT_RUNS_MAX], known = 1;                                  \
    run_end[0] = e0;                                                           \
    for (;;) {                                                                 \
      int runs = 0, r = 0;                                                     \
      for (int i = 0; i < n; runs++) {                                         \
        int e1 = r < known ? run_end[r++] : name##_run(v, i, n);               \
        int e2 = e1 >= n ? n : r < known ? run_end[r++] : name##_run(v, e1, n); \
        const T *a = v + i, *ea = v + e1, *b = ea, *eb = v + e2;               \
        T *o = t + i;                                                          \
        /* (in stretches from one side: the other's head stays put)       */ \
        while (a < ea && b < eb) {                                             \
          if (less(b, a))                                                      \
            do *o++ = *b++;                                                    \
            while (b < eb && less(b, a));                                      \
          else                                                                 \
            do *o++ = *a++;                                                    \
            while (a < ea && !less(b, a));                                     \
        }                                                                      \
        memcpy(o, a, (size_t)(ea - a) * sizeof *v);                            \
        memcpy(o + (ea - a), b, (size_t)(eb - b) * sizeof *v);                 \
        /* (run_end[runs] is read already: runs < r)                       */ \
        if (runs < SS_SORT_RUNS_MAX) run_end[runs] = e2;                       \
        i = e2;                                                                \
      }                                                                        \
      known = runs < SS_SORT_RUNS_MAX ? runs : SS_SORT_RUNS_MAX;               \
      T *w = v;                                                                \
      v = t;                                                                   \
      t = w;                                                                   \
      if (runs <= 1) return v;                                                 \
    }                                                                          \
  }                                                                            \
  static inline SS_SORT_RUNS_MAYBE_UNUSED T *name(T *v, T *t, int n)           \
  {                                                                            \
    return name##_from(v, t, n, 0);                                            \
  }

#endif /* SS_SORT_RUNS_H */
