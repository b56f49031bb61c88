/* The pixel model on synthetic log-intensity signals with known answers. */
#include "check.h"
#include "core/pixel.h"

#include <math.h>

typedef struct {
    float t;
    int p;
} ev_t;

/* Feeds log intensity l(t) = l0 + slope * t sampled at n uniform times over [0, T] (the first
 * at t = 0 sets the reference); collects events. */
static int run_ramp(const evr_pixel_params *p, float l0, float slope, float T, int n, ev_t *out,
                    int max)
{
    evr_pixel_state s;
    int k, count = 0;
    evr_pixel_reset(&s);
    for (k = 0; k <= n; k++) {
        float t = T * (float)k / (float)n;
        float intensity = expf(l0 + slope * t);
        evr_pixel_span sp;
        float te;
        int pol;
        if (!evr_pixel_begin(&s, p, t, intensity, &sp)) continue;
        while (evr_pixel_next(&s, p, &sp, &te, &pol)) {
            if (count < max) {
                out[count].t = te;
                out[count].p = pol;
            }
            count++;
        }
        evr_pixel_end(&s, &sp);
    }
    return count;
}

int main(void)
{
    evr_pixel_params p = {
        .pos_thres = 0.2f, .neg_thres = 0.25f, .refractory = 0.0f, .log_floor = 1e-3f};
    ev_t ev[512];
    int i, n;

    /* rising by R = 2.1 over 1 s: floor(R / 0.2) = 10 ON events at t_m = m * 0.2 / 2.1 */
    n = run_ramp(&p, 0.0f, 2.1f, 1.0f, 10, ev, 512);
    CHECK(n == 10);
    for (i = 0; i < n && i < 10; i++) {
        CHECK(ev[i].p == 1);
        CHECK_NEAR(ev[i].t, (i + 1) * 0.2 / 2.1, 2e-5);
    }
    /* the same ramp sampled very coarsely (2 samples) gives the same crossing times: they are
     * interpolated, not snapped to samples */
    n = run_ramp(&p, 0.0f, 2.1f, 1.0f, 1, ev, 512);
    CHECK(n == 10);
    for (i = 0; i < n && i < 10; i++) CHECK_NEAR(ev[i].t, (i + 1) * 0.2 / 2.1, 2e-5);

    /* falling by 1.3 with the OFF threshold 0.25: floor(1.3/0.25) = 5 OFF events */
    n = run_ramp(&p, 1.0f, -1.3f, 1.0f, 7, ev, 512);
    CHECK(n == 5);
    for (i = 0; i < n && i < 5; i++) {
        CHECK(ev[i].p == 0);
        CHECK_NEAR(ev[i].t, (i + 1) * 0.25 / 1.3, 2e-5);
    }

    /* below the threshold: nothing */
    n = run_ramp(&p, 0.0f, 0.19f, 1.0f, 50, ev, 512);
    CHECK(n == 0);

    /* a step spanning several thresholds within one sample interval: several events, in order,
     * at distinct interpolated times inside the interval */
    {
        evr_pixel_state s;
        evr_pixel_span sp;
        float te, last = -1.0f;
        int pol, count = 0;
        evr_pixel_reset(&s);
        evr_pixel_begin(&s, &p, 0.0f, 1.0f, &sp);
        CHECK(evr_pixel_begin(&s, &p, 0.01f, expf(1.05f), &sp) == 1);
        while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {
            CHECK(pol == 1);
            CHECK(te > last && te <= 0.01f);
            last = te;
            count++;
        }
        evr_pixel_end(&s, &sp);
        CHECK(count == 5);
        CHECK_NEAR(s.ref, 1.0, 1e-5);
    }

    /* refractory 2.5 ms on a ramp crossing a threshold every 1 ms: after each event the pixel is
     * blind 2.5 ms, then its reference resets to the level at wake-up, so events come every
     * 3.5 ms: at 1, 4.5, 8, ... ms; never two closer than the period */
    {
        evr_pixel_params pr = {
            .pos_thres = 0.2f, .neg_thres = 0.2f, .refractory = 2.5e-3f, .log_floor = 1e-3f};
        float slope = 0.2f / 1e-3f; /* one threshold per ms */
        n = run_ramp(&pr, 0.0f, slope, 0.02f, 200, ev, 512);
        CHECK(n == 6); /* 1, 4.5, 8, 11.5, 15, 18.5 ms */
        for (i = 0; i < n && i < 6; i++) CHECK_NEAR(ev[i].t, 1e-3 + 3.5e-3 * i, 3e-6);
        for (i = 1; i < n; i++) CHECK(ev[i].t - ev[i - 1].t >= pr.refractory - 1e-6f);
        /* with coarse samples the wake-up and reset happen inside a sample interval: same times */
        n = run_ramp(&pr, 0.0f, slope, 0.02f, 7, ev, 512);
        CHECK(n == 6);
        for (i = 0; i < n && i < 6; i++) CHECK_NEAR(ev[i].t, 1e-3 + 3.5e-3 * i, 3e-6);
    }

    /* segment rebasing keeps the crossing times continuous across segments */
    {
        evr_pixel_state s;
        evr_pixel_span sp;
        float te;
        int pol, count = 0;
        evr_pixel_reset(&s);
        evr_pixel_begin(&s, &p, 0.9f, 1.0f, &sp); /* last sample of segment 0 (length 1) */
        evr_pixel_end_segment(&s, 1.0f);
        CHECK_NEAR(s.t_prev, -0.1, 1e-6);
        CHECK(evr_pixel_begin(&s, &p, 0.1f, expf(0.3f), &sp)); /* first sample of segment 1 */
        while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {
            count++;
            CHECK_NEAR(te, -0.1 + 0.2 * (0.2 / 0.3), 1e-5);
        }
        CHECK(count == 1);
    }

    /* the log response is continuous with a continuous slope at the floor */
    CHECK_NEAR(evr_log_response(1e-3f, 1e-3f), logf(1e-3f), 1e-6);
    CHECK_NEAR((evr_log_response(1.0001e-3f, 1e-3f) - evr_log_response(0.9999e-3f, 1e-3f)) / 2e-7,
               1000.0, 10.0);
    CHECK(isfinite(evr_log_response(0.0f, 1e-3f)));
    return check_report("test_pixel");
}
