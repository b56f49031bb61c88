/* labels_compare A.h5 B.h5: how far two labels.h5 files agree, as one line of JSON, by the
 * criteria of tests/test_cuda_labels.py (which uses h5py where it can, this where it cannot: the
 * GPU machine has no h5py and no network to install it; scripts/gpu-pack.sh carries this
 * program beside evray):
 *   same   the share of pixels (all frames) with the same instance id
 *   seen   pixels where both see the same surface (same id, not 0)
 *   depth  the share of those with |a - b| <= 1e-3 |a|
 *   flow   the share of those with both components |a - b| <= 1e-2 px/s + 1e-3 |a|
 * (depth and flow 1 when seen is 0). Files of different sizes, frame counts or frame times are
 * not compared: one error line, exit 1. Reads through evray's own reader (io/labels_read.c). */
#include "evray_experimental.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct {
    float *depth, *flow;
    uint32_t *inst;
} frame_bufs;

static int alloc_bufs(frame_bufs *b, size_t n)
{
    b->depth = malloc(n * sizeof *b->depth);
    b->flow = malloc(2 * n * sizeof *b->flow);
    b->inst = malloc(n * sizeof *b->inst);
    return b->depth && b->flow && b->inst;
}

static void free_bufs(frame_bufs *b)
{
    free(b->depth);
    free(b->flow);
    free(b->inst);
}

static int fail(const char *msg)
{
    fprintf(stderr, "labels_compare: error: %s\n", msg);
    return 1;
}

int main(int argc, char **argv)
{
    evr_labels_info ia, ib;
    evr_error err = {{0}};
    frame_bufs a = {0}, b = {0};
    size_t n, k, i, same = 0, seen = 0, depth_ok = 0, flow_ok = 0;
    int rc = 1;
    char msg[600];
    if (argc != 3) {
        fprintf(stderr, "usage: labels_compare A/labels.h5 B/labels.h5\n");
        return 2;
    }
    if (evr_labels_read_info(argv[1], &ia, &err) != EVR_OK) return fail(err.msg);
    if (evr_labels_read_info(argv[2], &ib, &err) != EVR_OK) {
        evr_labels_info_free(&ia);
        return fail(err.msg);
    }
    if (ia.frames != ib.frames || ia.width != ib.width || ia.height != ib.height) {
        snprintf(msg, sizeof msg, "%s has %zu frames of %dx%d, %s %zu of %dx%d", argv[1], ia.frames,
                 ia.width, ia.height, argv[2], ib.frames, ib.width, ib.height);
        fail(msg);
        goto done;
    }
    for (k = 0; k < ia.frames; k++)
        if (fabs(ia.t[k] - ib.t[k]) > 1e-9) {
            snprintf(msg, sizeof msg, "frame %zu is at %.9g s in %s, %.9g s in %s", k, ia.t[k],
                     argv[1], ib.t[k], argv[2]);
            fail(msg);
            goto done;
        }
    n = (size_t)ia.width * (size_t)ia.height;
    if (!alloc_bufs(&a, n) || !alloc_bufs(&b, n)) {
        fail("out of memory");
        goto done;
    }
    for (k = 0; k < ia.frames; k++) {
        if (evr_labels_read_frame(argv[1], &ia, k, a.depth, a.inst, a.flow, &err) != EVR_OK ||
            evr_labels_read_frame(argv[2], &ib, k, b.depth, b.inst, b.flow, &err) != EVR_OK) {
            fail(err.msg);
            goto done;
        }
        for (i = 0; i < n; i++) {
            int f_ok = 1;
            if (a.inst[i] != b.inst[i]) continue;
            same++;
            if (a.inst[i] == 0) continue;
            seen++;
            /* written as "within", so that NaN fails as in the Python criteria */
            depth_ok += fabs((double)a.depth[i] - b.depth[i]) <= 1e-3 * fabs((double)a.depth[i]);
            for (int c = 0; c < 2; c++) {
                double fa = a.flow[2 * i + c], fb = b.flow[2 * i + c];
                if (!(fabs(fa - fb) <= 1e-2 + 1e-3 * fabs(fa))) f_ok = 0;
            }
            flow_ok += (size_t)f_ok;
        }
    }
    printf("{\"same\": %.17g, \"depth\": %.17g, \"flow\": %.17g, \"seen\": %zu, \"frames\": %zu, "
           "\"width\": %d, \"height\": %d}\n",
           (double)same / ((double)n * (double)ia.frames),
           seen ? (double)depth_ok / (double)seen : 1.0,
           seen ? (double)flow_ok / (double)seen : 1.0, seen, ia.frames, ia.width, ia.height);
    rc = 0;
done:
    free_bufs(&a);
    free_bufs(&b);
    evr_labels_info_free(&ia);
    evr_labels_info_free(&ib);
    return rc;
}
