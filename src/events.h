/* Growable event arrays and the stable time sort every backend's output goes through. */
#ifndef EVR_EVENTS_H
#define EVR_EVENTS_H

#include <stddef.h>
#include "evray.h"

typedef struct {
    evr_event *data;
    size_t n, cap;
} evr_event_vec;

/* Makes room for at least extra more events; returns 0 when out of memory. */
int evr_event_vec_reserve(evr_event_vec *v, size_t extra);
static inline int evr_event_vec_push(evr_event_vec *v, evr_event e)
{
    if (v->n == v->cap && !evr_event_vec_reserve(v, 1)) return 0;
    v->data[v->n++] = e;
    return 1;
}
int evr_event_vec_append(evr_event_vec *v, const evr_event *e, size_t n);
void evr_event_vec_free(evr_event_vec *v);

/* The file order: by t, then y, then x. */
static inline int evr_event_key_less(const evr_event *a, const evr_event *b)
{
    if (a->t != b->t) return a->t < b->t;
    if (a->y != b->y) return a->y < b->y;
    return a->x < b->x;
}

/* The number of leading events of ev[0 .. n) (sorted by t) with t < limit: a binary search. */
size_t evr_events_before(const evr_event *ev, size_t n, int64_t limit);

/* Sorts by (t, y, x), stable, so equal keys keep their input order (deterministic when the input
 * order is). scratch is grown as needed and may be reused between calls. */
int evr_events_sort(evr_event_vec *v, evr_event_vec *scratch);

/* Merges n events sorted by (t, y, x) into v, also sorted; events of v come first among equal
 * keys. */
int evr_events_merge(evr_event_vec *v, const evr_event *ev, size_t n, evr_event_vec *scratch);

/* The same for events already appended to v: merges its sorted runs v[0 .. h) and v[h .. n) in
 * place, the first run's first among equal keys. Only the overlap moves: the first run's events
 * that the second run's first precedes go through scratch (a segment's events overlap the few
 * held back from the one before, not the many before those). */
int evr_events_merge_runs(evr_event_vec *v, size_t h, evr_event_vec *scratch);

#endif
