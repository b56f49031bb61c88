/* The segment planner (src/run/segment_planner.c): segments are planned in order, each taken slot
 * holds its own segment's plan (never one planned over it before release), the planner runs at
 * most EVR_PLANNER_SLOTS segments ahead of the releases, and stopping early leaves nothing
 * running. */
#include "check.h"
#include "run/segment_planner.h"

#include <string.h>

typedef struct {
    int next; /* the segment the planner should plan next */
    int out_of_order;
    int *released; /* segments released so far, read by the planner */
    int too_far;   /* planned a segment more than EVR_PLANNER_SLOTS past the releases */
} plan_state;

static void plan(void *user, int segment, evr_planned_segment *out)
{
    plan_state *s = user;
    if (segment != s->next) s->out_of_order = 1;
    s->next = segment + 1;
    if (segment - __atomic_load_n(s->released, __ATOMIC_ACQUIRE) >= EVR_PLANNER_SLOTS)
        s->too_far = 1;
    out->num_keys = segment;
    out->track_count[0] = segment;
    out->keys[0].trans.x = (float)segment;
}

int main(void)
{
    const int n = 2000;
    int released = 0, wrong = 0;
    plan_state s;
    memset(&s, 0, sizeof s);
    s.released = &released;
    evr_planner *p = evr_planner_start(n, 4, 2, plan, &s);
    CHECK(p != NULL);
    for (int i = 0; i < n; i++) {
        const evr_planned_segment *pl = evr_planner_take(p, i);
        if (pl->num_keys != i || pl->track_count[0] != i || pl->keys[0].trans.x != (float)i)
            wrong++;
        __atomic_store_n(&released, i + 1, __ATOMIC_RELEASE);
        evr_planner_release(p, i);
    }
    evr_planner_stop(p);
    CHECK(wrong == 0 && !s.out_of_order && !s.too_far && s.next == n);

    /* stopped after a few segments: the planner stops too (it is joined), nothing past the ring */
    memset(&s, 0, sizeof s);
    released = 0;
    s.released = &released;
    p = evr_planner_start(n, 4, 2, plan, &s);
    CHECK(p != NULL);
    CHECK(evr_planner_take(p, 0)->num_keys == 0);
    evr_planner_stop(p);
    CHECK(!s.out_of_order && s.next <= EVR_PLANNER_SLOTS);
    return check_report("test_segment_planner");
}
