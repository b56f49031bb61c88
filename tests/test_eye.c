/* The eye scenes' animation (src/scene/demo_eye.c): "eye" is 30 s long; its eyeball and lids are
 * exactly still during a fixation (the keys of a fixation hold bit-identical rotations, and the
 * world rotation evaluated in it is the same), move during saccades (keys every 2 ms) and blinks
 * (7-9 of them); gaze stays within the plan's limits. "eye-drift" is the same plan with slow
 * drift: it moves within a fixation, by less than 0.2 degrees. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "evray.h"
#include "scene/scene.h"

static int find_node(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_nodes; i++)
        if (strcmp(s->nodes[i].name, name) == 0) return i;
    return -1;
}

/* Largest difference between two matrices' entries. */
static double m34_diff(const evr_m34 *a, const evr_m34 *b)
{
    double d = 0.0;
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++)
            if (fabs((double)a->m[i][j] - b->m[i][j]) > d)
                d = fabs((double)a->m[i][j] - b->m[i][j]);
    return d;
}

static int same_key(const evr_curve *c, int i, int j)
{
    return memcmp(c->values + 4 * i, c->values + 4 * j, 4 * sizeof(float)) == 0;
}

/* Rotation angle of key i in degrees. */
static double key_angle(const evr_curve *c, int i)
{
    double w = fabs((double)c->values[4 * i]);
    return 2.0 * acos(w > 1.0 ? 1.0 : w) * 180.0 / 3.14159265358979323846;
}

static evr_scene *load(const char *name)
{
    evr_scene *s = NULL;
    evr_error err;
    err.msg[0] = 0;
    CHECK_OK(evr_demo_load(name, &s, &err));
    if (!s) fprintf(stderr, "%s: %s\n", name, err.msg);
    return s;
}

int main(void)
{
    evr_scene *eye = load("eye"), *drift = load("eye-drift");
    int node[3], dnode[3], k, i, runs = 0, blinks = 0, closed = 0, nmid = 0;
    double first_a = -1.0, first_b = -1.0, max_gaze = 0.0, mid[128];
    const char *names[3] = {"eyeball", "upper_lid", "lower_lid"};
    const evr_curve *c;
    if (!eye || !drift) return check_report("test_eye");

    CHECK_NEAR(eye->anim_start, 0.0, 0.0);
    CHECK_NEAR(eye->anim_end, 30.0, 0.0);
    CHECK_NEAR(drift->anim_end, 30.0, 0.0);
    for (k = 0; k < 3; k++) {
        node[k] = find_node(eye, names[k]);
        dnode[k] = find_node(drift, names[k]);
        CHECK(node[k] >= 0 && dnode[k] >= 0);
        if (node[k] < 0 || dnode[k] < 0) return check_report("test_eye");
        CHECK(eye->nodes[node[k]].r_curve.num_keys == eye->nodes[node[0]].r_curve.num_keys);
    }
    c = &eye->nodes[node[0]].r_curve;
    printf("eye: %d keys per node; eye-drift: %d\n", c->num_keys,
           drift->nodes[dnode[0]].r_curve.num_keys);
    CHECK(c->num_keys > 1000 && c->num_keys < 5000);

    /* Between two keys either nothing moves (all three nodes hold the same values) or the keys
     * are dense (2 ms: a saccade or a blink). */
    for (i = 1; i < c->num_keys; i++) {
        int still = 1;
        for (k = 0; k < 3; k++) still &= same_key(&eye->nodes[node[k]].r_curve, i - 1, i);
        if (!still && c->times[i] - c->times[i - 1] > 0.002 + 1e-5) {
            fprintf(stderr, "eye: motion over %.6f s between keys at %.6f and %.6f\n",
                    c->times[i] - c->times[i - 1], c->times[i - 1], c->times[i]);
            CHECK(0);
        }
    }

    /* Gaze limits (15 deg yaw, 12 pitch, plus the 2 deg dip in a blink); blinks from the upper lid */
    for (i = 0; i < c->num_keys; i++) {
        double lid = key_angle(&eye->nodes[node[1]].r_curve, i);
        if (key_angle(c, i) > max_gaze) max_gaze = key_angle(c, i);
        if (!closed && lid > 25.0) blinks++;
        closed = lid > 25.0;
    }
    printf("eye: largest gaze angle %.2f deg, %d blinks\n", max_gaze, blinks);
    CHECK(max_gaze < 21.5);
    CHECK(blinks >= 7 && blinks <= 9);

    /* Fixations: runs of keys at least 150 ms long over which the eyeball's keys are identical. */
    for (i = 0; i < c->num_keys;) {
        int j = i;
        while (j + 1 < c->num_keys && same_key(c, i, j + 1)) j++;
        if (c->times[j] - c->times[i] >= 0.15) {
            double ta = c->times[i], tb = c->times[j], tm = 0.5 * (ta + tb);
            static const double fr[4] = {0.1, 0.33, 0.71, 0.93};
            runs++;
            if (first_a < 0.0 && ta > 0.0) {
                first_a = ta;
                first_b = tb;
            }
            for (k = 0; k < 3; k++) {
                evr_m34 a = evr_node_world_at(eye, node[k], ta),
                        b = evr_node_world_at(eye, node[k], tb);
                evr_m34 m = evr_node_world_at(eye, node[k], tm);
                int f;
                CHECK(same_key(&eye->nodes[node[k]].r_curve, i, j));
                /* at the fixation's keys and half way between them: bit-identical */
                CHECK(memcmp(&a, &b, sizeof a) == 0);
                CHECK(memcmp(&a, &m, sizeof a) == 0);
                /* Elsewhere inside it to float rounding: anim.c slerps identical keys as
                 * (1 - f) q + f q in float, which can differ from q in the last bit. */
                for (f = 0; f < 4; f++) {
                    evr_m34 x = evr_node_world_at(eye, node[k], ta + (tb - ta) * fr[f]);
                    CHECK(m34_diff(&a, &x) <= 1e-6);
                }
                /* the saccade after it moves the eye (and, with vertical gaze, the lids) */
                if (k == 0 && j + 1 < c->num_keys) {
                    evr_m34 s = evr_node_world_at(eye, node[0], tb + 0.010);
                    CHECK(m34_diff(&a, &s) > 1e-4);
                }
            }
            if (nmid < 128) mid[nmid++] = tm;
        }
        i = j + 1;
    }
    printf("eye: %d fixations of >= 150 ms without a blink\n", runs);
    CHECK(runs >= 60 && runs <= 100);

    /* eye-drift: the same plan, but moving within a fixation (keys every <= 25 ms) */
    c = &drift->nodes[dnode[0]].r_curve;
    for (i = 1; i < c->num_keys; i++) CHECK(c->times[i] - c->times[i - 1] <= 0.025 + 1e-5);
    CHECK(first_a > 0.0);
    if (first_a > 0.0) {
        double tm = 0.5 * (first_a + first_b);
        evr_m34 a = evr_node_world_at(drift, dnode[0], first_a),
                m = evr_node_world_at(drift, dnode[0], tm);
        evr_m34 e = evr_node_world_at(eye, node[0], tm);
        CHECK(memcmp(&a, &m, sizeof a) != 0);
        CHECK(m34_diff(&a, &m) > 1e-6);
        CHECK(m34_diff(&e, &m) < 0.2 * 3.14159265 / 180.0); /* drift is below 0.2 degrees */
    }
    for (k = 0; k < nmid; k++) { /* the same plan: every fixation within the drift's amplitude */
        evr_m34 a = evr_node_world_at(drift, dnode[0], mid[k]),
                b = evr_node_world_at(eye, node[0], mid[k]);
        CHECK(m34_diff(&a, &b) < 0.2 * 3.14159265 / 180.0);
    }
    evr_scene_release(eye);
    evr_scene_release(drift);
    return check_report("test_eye");
}
