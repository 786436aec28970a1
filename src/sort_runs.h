/* sort_runs.h -- a natural merge sort for arrays that come in a few sorted
 * runs (the contacts of one collider, the points of a polygon), written
 * once for any element type.
 *
 * SS_SORT_RUNS(name, T, less) defines
 *
 *   static T *name(T *v, T *t, int n)
 *
 * which sorts the n elements of v, with the scratch t of n elements, by
 * less(const T *a, const T *b) (a strict order), and returns whichever of v
 * and t ends holding them (v when they were sorted already, or all but a
 * short tail: SS_SORT_RUNS_TAIL).  Each pass finds the runs -- non-
 * decreasing, or strictly decreasing and then reversed in place -- and
 * merges them pairwise, taking the left element on ties: the sort is
 * stable, so its result is the one stable order, whatever the runs.
 * Linear for input already sorted, a few passes for a few runs; no
 * allocation and no call through a pointer per comparison (the element
 * type and comparison are the caller's, inlined). */
#ifndef SS_SORT_RUNS_H
#define SS_SORT_RUNS_H

#include <string.h>

/* a first run followed by at most this many elements: those are inserted
 * into it in place (a binary search and a move each) instead of merged
 * through the scratch (every element copied): the joint rows after a
 * step's soil points, where one PD row's dof comes before another's */
#define SS_SORT_RUNS_TAIL 8

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
  static T *name(T *v, T *t, int n)                                            \
  {                                                                            \
    int e0 = name##_run(v, 0, n);                                              \
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
    for (;;) {                                                                 \
      int runs = 0;                                                            \
      for (int i = 0; i < n; runs++) {                                         \
        int e1 = name##_run(v, i, n), e2 = e1 < n ? name##_run(v, e1, n) : n;  \
        int a = i, b = e1, o = i;                                              \
        while (a < e1 && b < e2) t[o++] = less(&v[b], &v[a]) ? v[b++] : v[a++]; \
        while (a < e1) t[o++] = v[a++];                                        \
        while (b < e2) t[o++] = v[b++];                                        \
        i = e2;                                                                \
      }                                                                        \
      T *w = v;                                                                \
      v = t;                                                                   \
      t = w;                                                                   \
      if (runs <= 1) return v;                                                 \
    }                                                                          \
  }

#endif /* SS_SORT_RUNS_H */
