/* The event sort is a stable sort by (t, y, x). */
#include "check.h"
#include "events.h"
#include "core/rng.h"

#include <stdint.h>
#include <stdlib.h>

static int cmp(const void *a, const void *b)
{
    const evr_event *x = a, *y = b;
    if (x->t != y->t) return x->t < y->t ? -1 : 1;
    if (x->y != y->y) return x->y < y->y ? -1 : 1;
    if (x->x != y->x) return x->x < y->x ? -1 : 1;
    return 0;
}

int main(void)
{
    evr_event_vec v = {0}, scratch = {0};
    size_t n = 100000, i;
    int64_t base = 5000000000LL; /* large absolute times */
    for (i = 0; i < n; i++) {
        uint64_t h = evr_hash4(7, i, 0, 0);
        evr_event e = {0};
        e.t = base + (int64_t)(h % 70000);
        e.x = (uint16_t)((h >> 20) % 1280);
        e.y = (uint16_t)((h >> 40) % 720);
        e.p = (int8_t)(i & 1);
        CHECK(evr_event_vec_push(&v, e));
    }
    evr_event *ref = malloc(n * sizeof *ref);
    for (i = 0; i < n; i++) ref[i] = v.data[i];
    /* a stable reference: merge order by index through the tie-break on p, which here encodes
     * parity of the input index, is not enough; compare keys and check stability separately */
    qsort(ref, n, sizeof *ref, cmp);
    CHECK(evr_events_sort(&v, &scratch));
    CHECK(v.n == n);
    int same_keys = 1;
    for (i = 0; i < n; i++)
        if (v.data[i].t != ref[i].t || v.data[i].x != ref[i].x || v.data[i].y != ref[i].y)
            same_keys = 0;
    CHECK(same_keys);
    free(ref);

    /* the events before a time: what a linear scan counts, ties and both ends included */
    {
        int64_t limits[] = {INT64_MIN,       base - 1,     base,         base + 1, base + 12345,
                            v.data[n / 2].t, base + 69999, base + 70000, INT64_MAX};
        int before_ok = evr_events_before(v.data, 0, base) == 0;
        for (size_t k = 0; k < sizeof limits / sizeof limits[0]; k++) {
            size_t m = 0;
            while (m < n && v.data[m].t < limits[k]) m++;
            if (evr_events_before(v.data, n, limits[k]) != m) before_ok = 0;
        }
        CHECK(before_ok);
    }

    /* keys wider than 64 bits: full-range x and y, times spanning most of int64 */
    {
        size_t m = 20000, k;
        v.n = 0;
        for (k = 0; k < m; k++) {
            uint64_t h = evr_hash4(9, k, 0, 0), g = evr_hash4(9, k, 1, 0);
            evr_event e = {0};
            e.t = (int64_t)(h >> 2) - (INT64_C(1) << 61) + (int64_t)(k % 5);
            if (k % 7 == 0) e.t = INT64_C(-4000000000000000000) + (int64_t)(k % 3); /* ties */
            e.x = (uint16_t)g;
            e.y = (uint16_t)(g >> 16);
            if (k % 11 == 0) e.x = 65535;
            e.p = (int8_t)(k & 1);
            CHECK(evr_event_vec_push(&v, e));
        }
        evr_event *wide = malloc(m * sizeof *wide);
        for (k = 0; k < m; k++) wide[k] = v.data[k];
        qsort(wide, m, sizeof *wide, cmp);
        CHECK(evr_events_sort(&v, &scratch));
        int wide_ok = v.n == m;
        for (k = 0; wide_ok && k < m; k++)
            if (v.data[k].t != wide[k].t || v.data[k].x != wide[k].x || v.data[k].y != wide[k].y)
                wide_ok = 0;
        CHECK(wide_ok);
        free(wide);
    }

    /* stability: equal keys keep input order */
    v.n = 0;
    for (i = 0; i < 1000; i++) {
        evr_event e = {base + (int64_t)(i % 3), 5, 5, (int8_t)(i % 2), 0};
        evr_event_vec_push(&v, e);
    }
    CHECK(evr_events_sort(&v, &scratch));
    int stable = 1;
    for (i = 1; i < v.n; i++)
        if (v.data[i].t == v.data[i - 1].t && v.data[i].p == v.data[i - 1].p)
            stable = 0; /* alternates */
    CHECK(stable);
    /* merging sorted runs in place (evr_events_merge_runs, evr_events_merge): the order of a
     * plain two-way merge that takes the first run's event on equal keys, for runs that overlap
     * a little, a lot, not at all, and with ties across them (p tells the run apart) */
    {
        const size_t lens[][2] = {{0, 5},       {5, 0},   {300, 2000}, {2000, 300},
                                  {1000, 1000}, {1, 700}, {700, 1}};
        const int64_t shifts[] = {0, 40, 200, 1000};
        evr_event_vec runs = {0}, ref2 = {0};
        int merge_ok = 1;
        for (size_t c = 0; c < sizeof lens / sizeof lens[0]; c++) {
            for (size_t sh = 0; sh < sizeof shifts / sizeof shifts[0]; sh++) {
                runs.n = 0;
                for (int r = 0; r < 2; r++)
                    for (size_t k = 0; k < lens[c][r];
                         k++) { /* run r: sorted keys, t from a small range */
                        evr_event e = {0};
                        e.t = base + (int64_t)(k / 3) + (r ? shifts[sh] : 0);
                        e.y = (uint16_t)(k % 3 == 2 ? 1 : 0);
                        e.x = (uint16_t)(k % 3 == 1 ? 7 : 3);
                        if (e.y) e.x = 0;
                        e.p = (int8_t)r;
                        CHECK(evr_event_vec_push(&runs, e));
                    }
                const size_t h = lens[c][0], total = runs.n;
                ref2.n = 0; /* the reference: a plain merge */
                size_t a = 0, b = h;
                while (a < h || b < total) {
                    int take_b =
                        a == h || (b < total && evr_event_key_less(&runs.data[b], &runs.data[a]));
                    CHECK(evr_event_vec_push(&ref2, runs.data[take_b ? b++ : a++]));
                }
                /* evr_events_merge: the first run, the second merged into it */
                evr_event_vec first = {0};
                CHECK(evr_event_vec_append(&first, runs.data, h));
                CHECK(evr_events_merge(&first, runs.data + h, total - h, &scratch));
                CHECK(evr_events_merge_runs(&runs, h, &scratch));
                for (size_t k = 0; k < total; k++) {
                    const evr_event *x = &runs.data[k], *y = &ref2.data[k], *z = &first.data[k];
                    if (x->t != y->t || x->x != y->x || x->y != y->y || x->p != y->p) merge_ok = 0;
                    if (z->t != y->t || z->x != y->x || z->y != y->y || z->p != y->p) merge_ok = 0;
                }
                if (first.n != total) merge_ok = 0;
                evr_event_vec_free(&first);
                if (runs.n != total) merge_ok = 0;
            }
        }
        CHECK(merge_ok);
        evr_event_vec_free(&runs);
        evr_event_vec_free(&ref2);
    }
    evr_event_vec_free(&v);
    evr_event_vec_free(&scratch);
    return check_report("test_events_sort");
}
