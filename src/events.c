#include "events.h"

#include <stdlib.h>
#include <string.h>

int evr_event_vec_reserve(evr_event_vec *v, size_t extra)
{
    if (v->n + extra <= v->cap) return 1;
    size_t cap = v->cap ? v->cap : 1024;
    while (cap < v->n + extra) cap *= 2;
    evr_event *p = realloc(v->data, cap * sizeof *p);
    if (!p) return 0;
    v->data = p;
    v->cap = cap;
    return 1;
}

int evr_event_vec_append(evr_event_vec *v, const evr_event *e, size_t n)
{
    if (!n) return 1;
    if (!evr_event_vec_reserve(v, n)) return 0;
    memcpy(v->data + v->n, e, n * sizeof *e);
    v->n += n;
    return 1;
}

void evr_event_vec_free(evr_event_vec *v)
{
    free(v->data);
    v->data = NULL;
    v->n = v->cap = 0;
}

size_t evr_events_before(const evr_event *ev, size_t n, int64_t limit)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (ev[mid].t < limit) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* LSD radix sort on 16-bit digits of the key (t - t_min, y, x); passes whose digit is the same for
 * every event are skipped, so a segment typically needs four or five passes. */
int evr_events_sort(evr_event_vec *v, evr_event_vec *scratch)
{
    size_t n = v->n, i;
    if (n < 2) return 1;
    int64_t tmin = v->data[0].t, tmax = v->data[0].t;
    for (i = 1; i < n; i++) {
        if (v->data[i].t < tmin) tmin = v->data[i].t;
        if (v->data[i].t > tmax) tmax = v->data[i].t;
    }
    uint64_t span = (uint64_t)(tmax - tmin);
    int tdigits = 0;
    while (tdigits < 4 && span >> (16 * tdigits)) tdigits++; /* a shift by 64 is undefined */
    scratch->n = 0;
    if (!evr_event_vec_reserve(scratch, n)) return 0;
    size_t *count = malloc(65536 * sizeof *count);
    if (!count) return 0;
    evr_event *src = v->data, *dst = scratch->data;
    int pass;
    for (pass = 0; pass < 2 + tdigits; pass++) {
        memset(count, 0, 65536 * sizeof *count);
        for (i = 0; i < n; i++) {
            unsigned d =
                pass == 0 ? src[i].x
                : pass == 1
                    ? src[i].y
                    : (unsigned)(((uint64_t)(src[i].t - tmin) >> (16 * (pass - 2))) & 0xffff);
            count[d]++;
        }
        size_t sum = 0, d;
        int trivial = 0;
        for (d = 0; d < 65536; d++) {
            size_t c = count[d];
            if (c == n) trivial = 1;
            count[d] = sum;
            sum += c;
        }
        if (trivial) continue;
        for (i = 0; i < n; i++) {
            unsigned dg =
                pass == 0 ? src[i].x
                : pass == 1
                    ? src[i].y
                    : (unsigned)(((uint64_t)(src[i].t - tmin) >> (16 * (pass - 2))) & 0xffff);
            dst[count[dg]++] = src[i];
        }
        evr_event *tmp = src;
        src = dst;
        dst = tmp;
    }
    free(count);
    if (src != v->data) { /* result sits in scratch: swap the buffers */
        evr_event *d = v->data;
        size_t c = v->cap;
        v->data = scratch->data;
        v->cap = scratch->cap;
        scratch->data = d;
        scratch->cap = c;
    }
    scratch->n = 0;
    return 1;
}

int evr_events_merge_runs(evr_event_vec *v, size_t h, evr_event_vec *scratch)
{
    evr_event *d = v->data;
    const size_t n = v->n;
    if (h == 0 || h >= n || !evr_event_key_less(&d[h], &d[h - 1])) return 1; /* already in order */
    /* lo: the first event of the first run that the second run's first precedes; end: the first
     * event of the second run that the first run's last does not follow */
    size_t lo = 0, hi = h;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (evr_event_key_less(&d[h], &d[mid])) hi = mid;
        else lo = mid + 1;
    }
    size_t a = h, b = n;
    while (a < b) {
        size_t mid = a + (b - a) / 2;
        if (evr_event_key_less(&d[mid], &d[h - 1])) a = mid + 1;
        else b = mid;
    }
    const size_t end = a, m = h - lo;
    scratch->n = 0;
    if (!evr_event_vec_append(scratch, d + lo, m)) return 0;
    /* forward merge into d[lo ..): the write index never passes the second run's read index */
    size_t i = 0, j = h, k = lo;
    while (i < m && j < end)
        d[k++] = evr_event_key_less(&d[j], &scratch->data[i]) ? d[j++] : scratch->data[i++];
    while (i < m) d[k++] = scratch->data[i++];
    scratch->n = 0;
    return 1;
}

int evr_events_merge(evr_event_vec *v, const evr_event *ev, size_t n, evr_event_vec *scratch)
{
    const size_t h = v->n;
    if (!n) return 1;
    if (!evr_event_vec_append(v, ev, n)) return 0;
    return evr_events_merge_runs(v, h, scratch);
}
