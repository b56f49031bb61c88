/* The sensor model of core/pixel.h (threshold mismatch, bandwidth, leak, shot noise, hot pixels,
 * refractory period, timestamps), driven directly for many pixels over long times the way the
 * backends drive it (segments, per-pixel sample phases, rebasing), against predicted statistics
 * and closed forms. */
#include "check.h"
#include "core/pixel.h"
#include "core/rng.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W 1000 /* pixel p is (p % W, p / W) */

static evr_pixel_params base_params(void)
{
    evr_pixel_params p;
    memset(&p, 0, sizeof p);
    p.pos_thres = 0.2f;
    p.neg_thres = 0.2f;
    p.log_floor = 1e-3f;
    p.full_intensity = 1.0f;
    p.leak_jitter = 0.1f;
    p.hot_rate = 100.0f;
    p.time_res_us = 1;
    p.seed = 7;
    return p;
}

/* Linear intensity of pixel pix at absolute time t. */
typedef float (*intensity_fn)(int pix, double t, const void *user);

typedef struct {
    int *count_on, *count_off; /* per pixel */
    double *first, *last;      /* per pixel: first and last event time */
    double min_gap;            /* smallest gap between two events of one pixel */
    long long min_gap_us;      /* the same in quantized timestamps */
    long long total_on, total_off;
    long long not_multiple; /* timestamps that are not multiples of the resolution */
    double *times;          /* optional: event times of pixel 0 */
    int ntimes, max_times;
} tally;

static void tally_init(tally *t, int npix)
{
    memset(t, 0, sizeof *t);
    t->count_on = calloc((size_t)npix, sizeof(int));
    t->count_off = calloc((size_t)npix, sizeof(int));
    t->first = calloc((size_t)npix, sizeof(double));
    t->last = calloc((size_t)npix, sizeof(double));
    t->min_gap = 1e30;
    t->min_gap_us = (long long)1 << 60;
}

static void tally_free(tally *t)
{
    free(t->count_on);
    free(t->count_off);
    free(t->first);
    free(t->last);
    free(t->times);
}

/* Runs pixels [0, npix) for duration T in segments of length seg with n samples each, as the
 * backends do. */
static void drive(const evr_pixel_params *run, int npix, double T, double seg, int n,
                  intensity_fn I, const void *user, tally *out)
{
    int pix, i, k, nseg = (int)ceil(T / seg - 1e-9);
    for (pix = 0; pix < npix; pix++) {
        int x = pix % W, y = pix / W, seen = 0;
        evr_pixel_params pp;
        evr_pixel_state s;
        double prev = 0.0;
        long long prev_us = 0;
        float phi = evr_pixel_phase(run->seed, x, y);
        evr_pixel_params_at(run, x, y, &pp);
        evr_pixel_reset(&s);
        for (i = 0; i < nseg; i++) {
            double t0 = (double)i * seg;
            for (k = 0; k < n; k++) {
                float f = ((float)k + phi) / (float)n;
                evr_pixel_span sp;
                float te;
                int pol;
                if (!evr_pixel_begin(&s, &pp, f * (float)seg, I(pix, t0 + (double)f * seg, user),
                                     &sp))
                    continue;
                while (evr_pixel_next(&s, &pp, &sp, &te, &pol)) {
                    double t = t0 + (double)te;
                    long long us = evr_event_time_us(&pp, t, x, y);
                    if (pp.time_res_us > 1 && us % pp.time_res_us) out->not_multiple++;
                    if (pol) {
                        out->count_on[pix]++;
                        out->total_on++;
                    } else {
                        out->count_off[pix]++;
                        out->total_off++;
                    }
                    if (seen) {
                        if (t - prev < out->min_gap) out->min_gap = t - prev;
                        if (us - prev_us < out->min_gap_us) out->min_gap_us = us - prev_us;
                    } else {
                        out->first[pix] = t;
                    }
                    out->last[pix] = t;
                    if (pix == 0 && out->ntimes < out->max_times) out->times[out->ntimes++] = t;
                    prev = t;
                    prev_us = us;
                    seen = 1;
                }
                evr_pixel_end(&s, &sp);
            }
            evr_pixel_end_segment(&s, (float)seg);
        }
    }
}

static float constant_intensity(int pix, double t, const void *user)
{
    (void)pix;
    (void)t;
    return *(const float *)user;
}

/* Even pixels: log intensity rises by R over [0.1, 0.5] s; odd pixels: falls by R. */
static float ramp_intensity(int pix, double t, const void *user)
{
    double R = *(const double *)user, u = (t - 0.1) / 0.4;
    u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
    return (float)exp((pix & 1) ? R * (1.0 - u) : R * u);
}

/* Standard normal density. */
static double phi_n(double z) { return exp(-0.5 * z * z) / sqrt(2.0 * 3.14159265358979); }

static void test_mismatch(void)
{
    const int npix = 40000;
    const double R = 4.1; /* nominal: floor(4.1 / 0.2) = 20 events */
    evr_pixel_params p = base_params();
    tally t;
    int i;
    /* the thresholds themselves: mean and spread as set, ON and OFF independent */
    p.sigma_thres = 0.02f;
    {
        double s1 = 0, s2 = 0, o1 = 0, o2 = 0, so = 0;
        for (i = 0; i < npix; i++) {
            evr_pixel_params q;
            evr_pixel_params_at(&p, i % W, i / W, &q);
            s1 += q.pos_thres;
            s2 += (double)q.pos_thres * q.pos_thres;
            o1 += q.neg_thres;
            o2 += (double)q.neg_thres * q.neg_thres;
            so += (double)q.pos_thres * q.neg_thres;
        }
        double m = s1 / npix, sd = sqrt(s2 / npix - m * m), mo = o1 / npix,
               sdo = sqrt(o2 / npix - mo * mo);
        double corr = (so / npix - m * mo) / (sd * sdo);
        CHECK_NEAR(m, 0.2, 3.0 * 0.02 / sqrt(npix) + 1e-6);
        CHECK_NEAR(mo, 0.2, 3.0 * 0.02 / sqrt(npix) + 1e-6);
        CHECK_NEAR(sd, 0.02, 0.02 * 0.03);
        CHECK_NEAR(sdo, 0.02, 0.02 * 0.03);
        CHECK(fabs(corr) < 0.03);
    }
    /* the predicted distribution of floor(R / theta), theta ~ N(0.2, 0.02) */
    double em = 0, e2 = 0;
    for (i = -8000; i <= 8000; i++) {
        double z = i * 1e-3, th = 0.2 + 0.02 * z, w = phi_n(z) * 1e-3;
        double c = floor(R / (th < 0.01 ? 0.01 : th));
        em += w * c;
        e2 += w * c * c;
    }
    double esd = sqrt(e2 - em * em);
    tally_init(&t, npix);
    drive(&p, npix, 0.6, 1.0 / 30.0, 10, ramp_intensity, &R, &t);
    for (int pol = 0; pol < 2; pol++) { /* ON counts of even pixels, OFF counts of odd ones */
        double s1 = 0, s2 = 0;
        int m = 0, wrong = 0;
        for (i = pol; i < npix; i += 2) {
            int c = pol ? t.count_off[i] : t.count_on[i];
            wrong += pol ? t.count_on[i] : t.count_off[i];
            s1 += c;
            s2 += (double)c * c;
            m++;
        }
        double mean = s1 / m, sd = sqrt(s2 / m - mean * mean);
        printf(
            "mismatch sigma 0.02, ramp of %.1f: %s counts mean %.3f sd %.3f (predicted %.3f, %.3f)\n",
            R, pol ? "OFF" : "ON", mean, sd, em, esd);
        CHECK(wrong == 0);
        CHECK_NEAR(mean, em, 4.0 * esd / sqrt(m));
        CHECK_NEAR(sd, esd, 0.05 * esd);
    }
    /* a fixed pattern: the same counts when the ramp is seen again (the thresholds are a pure
     * function of seed and pixel) */
    {
        tally t2;
        tally_init(&t2, npix);
        drive(&p, npix, 0.6, 1.0 / 30.0, 7, ramp_intensity, &R, &t2);
        int same = 1;
        for (i = 0; i < npix; i++)
            same &= t.count_on[i] == t2.count_on[i] && t.count_off[i] == t2.count_off[i];
        CHECK(same);
        tally_free(&t2);
    }
    tally_free(&t);
    /* no mismatch: every pixel gives exactly 20 */
    p.sigma_thres = 0.0f;
    tally_init(&t, 2000);
    drive(&p, 2000, 0.6, 1.0 / 30.0, 10, ramp_intensity, &R, &t);
    {
        int all = 1;
        for (i = 0; i < 2000; i++) all &= (i & 1 ? t.count_off[i] : t.count_on[i]) == 20;
        CHECK(all);
    }
    tally_free(&t);
}

static void test_leak(void)
{
    const int npix = 2000;
    const double T = 30.0;
    const float I = 0.3f;
    evr_pixel_params p = base_params();
    tally t;
    int i, m = 0;
    double s1 = 0, s2 = 0, worst = 0;
    p.leak_rate = 1.0f;
    p.leak_jitter = 0.1f;
    p.sigma_thres = 0.02f; /* leak in units of the pixel's own threshold: the rate is unchanged */
    tally_init(&t, npix);
    drive(&p, npix, T, 1.0 / 30.0, 10, constant_intensity, &I, &t);
    double rate = (double)t.total_on / (npix * T);
    printf("leak 1 Hz, jitter 0.1: %.4f ON events/s per pixel, %lld OFF\n", rate, t.total_off);
    CHECK_NEAR(rate, 1.0, 0.1);
    CHECK_NEAR(rate, 1.0, 0.02);
    CHECK(t.total_off == 0);
    /* each static pixel fires periodically at its own rate: the intervals give it exactly */
    for (i = 0; i < npix; i++) {
        evr_pixel_params q;
        evr_pixel_params_at(&p, i % W, i / W, &q);
        double expect = q.leak / q.pos_thres;
        if (t.count_on[i] < 3) continue;
        double r = (t.count_on[i] - 1) / (t.last[i] - t.first[i]);
        if (fabs(r - expect) / expect > worst) worst = fabs(r - expect) / expect;
        s1 += r;
        s2 += r * r;
        m++;
    }
    double mean = s1 / m, sd = sqrt(s2 / m - mean * mean);
    printf(
        "leak: per-pixel rates mean %.4f sd %.4f, worst relative error vs the pixel's rate %.2g\n",
        mean, sd, worst);
    CHECK(m > npix * 9 / 10);
    CHECK(worst < 1e-3);
    CHECK_NEAR(mean, 1.0, 0.01);
    CHECK_NEAR(sd, 0.1, 0.01);
    /* random initial phases: the first leak events are spread over the first period, not
     * synchronous */
    {
        int early = 0;
        for (i = 0; i < npix; i++) early += t.first[i] < 0.5;
        CHECK(early > npix * 4 / 10 && early < npix * 6 / 10);
    }
    tally_free(&t);
}

static void test_shot(void)
{
    const int npix = 2000;
    const double T = 20.0, R = 2.0;
    /* black, half and full brightness (and beyond: the fraction is clipped to 1) */
    const float levels[4] = {0.0f, 0.5f, 1.0f, 3.0f};
    const double expect[4] = {R, R * (1.0 - 0.75 * 0.5), R * 0.25, R * 0.25};
    evr_pixel_params p = base_params();
    int l;
    p.shot_rate = (float)R;
    for (l = 0; l < 4; l++) {
        tally t;
        tally_init(&t, npix);
        drive(&p, npix, T, 1.0 / 30.0, 10, constant_intensity, &levels[l], &t);
        double rate = (double)(t.total_on + t.total_off) / (npix * T);
        double on = (double)t.total_on / (double)(t.total_on + t.total_off);
        printf(
            "shot noise %.1f Hz at intensity %.1f: %.4f events/s per pixel (expected %.4f), ON share %.3f\n",
            R, (double)levels[l], rate, expect[l], on);
        CHECK_NEAR(rate, expect[l], 0.1 * expect[l]);
        CHECK_NEAR(rate, expect[l], 4.0 * sqrt(expect[l] / (npix * T)));
        CHECK_NEAR(on, 0.5, 0.02);
        tally_free(&t);
    }
    /* Poisson in continuous time: exponential gaps (coefficient of variation 1), and the same
     * event times whatever the sampling */
    {
        const float dark = 0.0f;
        tally a, b;
        int i, same = 1;
        tally_init(&a, 1);
        tally_init(&b, 1);
        a.max_times = b.max_times = 100000;
        a.times = malloc(sizeof(double) * 100000);
        b.times = malloc(sizeof(double) * 100000);
        p.shot_rate = 50.0f;
        drive(&p, 1, 100.0, 1.0 / 30.0, 10, constant_intensity, &dark, &a);
        drive(&p, 1, 100.0, 1.0 / 25.0, 3, constant_intensity, &dark, &b);
        double g1 = 0, g2 = 0;
        int ng = a.ntimes - 1;
        for (i = 1; i < a.ntimes; i++) {
            double g = a.times[i] - a.times[i - 1];
            g1 += g;
            g2 += g * g;
        }
        double gm = g1 / ng, cv = sqrt(g2 / ng - gm * gm) / gm;
        printf("shot noise 50 Hz on one pixel: %d events in 100 s, gap CV %.3f\n", a.ntimes, cv);
        CHECK_NEAR(a.ntimes / 100.0, 50.0, 4.0 * sqrt(50.0 / 100.0));
        CHECK_NEAR(cv, 1.0, 0.05);
        /* b's first sample comes later than a's: compare from 0.1 s on */
        int ia = 0, ib = 0;
        while (ia < a.ntimes && a.times[ia] < 0.1) ia++;
        while (ib < b.ntimes && b.times[ib] < 0.1) ib++;
        if (a.ntimes - ia != b.ntimes - ib) same = 0;
        for (; same && ia < a.ntimes && ib < b.ntimes; ia++, ib++)
            same &= fabs(a.times[ia] - b.times[ib]) <
                    2e-5; /* float rebasing drifts ~1e-9 s a segment */
        CHECK(same);
        tally_free(&a);
        tally_free(&b);
    }
}

static void test_hot(void)
{
    const int npix = 20000;
    const double T = 2.0, F = 0.01;
    const float I = 0.5f;
    evr_pixel_params p = base_params();
    tally t;
    int i, hot = 0, flagged = 0, agree = 1;
    p.hot_fraction = (float)F;
    p.hot_rate = 100.0f;
    tally_init(&t, npix);
    drive(&p, npix, T, 1.0 / 30.0, 10, constant_intensity, &I, &t);
    for (i = 0; i < npix; i++) {
        evr_pixel_params q;
        evr_pixel_params_at(&p, i % W, i / W, &q);
        hot += t.count_on[i] > 0;
        flagged += q.hot > 0.0f;
        agree &= (t.count_on[i] > 0) == (q.hot > 0.0f);
    }
    double rate = (double)t.total_on / (hot * T), sd = sqrt(npix * F * (1.0 - F));
    printf(
        "hot pixels 1%% at 100 Hz: %d of %d pixels fire (expected %.0f +- %.0f), %.2f ON events/s each, %lld OFF\n",
        hot, npix, npix * F, sd, rate, t.total_off);
    CHECK(agree);
    CHECK(hot == flagged);
    CHECK_NEAR(hot, npix * F, 4.0 * sd);
    CHECK_NEAR(rate, 100.0, 10.0);
    CHECK_NEAR(rate, 100.0, 4.0 * sqrt(100.0 / (hot * T)) + 0.5);
    CHECK(t.total_off == 0);
    tally_free(&t);
}

/* A busy pixel: a steep ramp up and down, shot noise, a hot pixel, leak. */
static float busy_intensity(int pix, double t, const void *user)
{
    (void)user;
    double ph = fmod(t + 0.01 * pix, 0.2);
    return (float)exp(ph < 0.1 ? 40.0 * ph : 40.0 * (0.2 - ph)) * 0.05f;
}

static void test_refractory(void)
{
    const int npix = 200;
    evr_pixel_params p = base_params();
    tally t;
    p.refractory = 1e-3f;
    p.sigma_thres = 0.03f;
    p.leak_rate = 5.0f;
    p.shot_rate = 30.0f;
    p.hot_fraction = 0.2f;
    p.hot_rate = 2000.0f;
    p.cutoff_hz = 300.0f;
    p.time_res_us = 1;
    tally_init(&t, npix);
    drive(&p, npix, 2.0, 1.0 / 30.0, 20, busy_intensity, NULL, &t);
    printf("refractory 1 ms with everything on: %lld events, smallest gap %.4g s (%lld us)\n",
           t.total_on + t.total_off, t.min_gap, t.min_gap_us);
    CHECK(t.total_on + t.total_off > 10000);
    CHECK(t.min_gap >= 1e-3 - 1e-6);
    CHECK(t.min_gap_us >= 1000);
    tally_free(&t);
    /* dead time: a Poisson source of rate r behind a refractory period tau is seen at
     * r / (1 + r tau) */
    {
        const float I = 0.5f;
        evr_pixel_params q = base_params();
        q.hot_fraction = 1.0f;
        q.hot_rate = 500.0f;
        q.refractory = 1e-3f;
        tally_init(&t, 200);
        drive(&q, 200, 5.0, 1.0 / 30.0, 10, constant_intensity, &I, &t);
        double rate = (double)t.total_on / (200 * 5.0);
        printf("hot pixels at 500 Hz behind 1 ms refractory: %.1f events/s (expected %.1f)\n", rate,
               500.0 / 1.5);
        CHECK_NEAR(rate, 500.0 / 1.5, 0.03 * 500.0 / 1.5);
        tally_free(&t);
    }
}

/* The filtered level the pixel holds after each sample. */
static void test_lowpass(void)
{
    evr_pixel_params p = base_params();
    p.cutoff_hz = 10.0f;
    /* step from I = 2 to I = 2e (both at or above full brightness: the full cutoff, tau = 1 / (2 pi 10)) */
    {
        const double tau = 1.0 / (2.0 * 3.14159265358979 * 10.0), La = log(2.0),
                     Lb = log(2.0) + 1.0;
        evr_pixel_state s;
        evr_pixel_span sp;
        float te;
        int pol, k, nev = 0, bad = 0;
        double worst = 0, ev[16];
        evr_pixel_reset(&s);
        evr_pixel_begin(&s, &p, 0.0f, 2.0f, &sp);
        for (k = 1; k <= 150; k++) { /* 9 tau: far from the level 1.0 the signal never reaches */
            float t = k == 1 ? 1e-7f : (float)(k - 1) * 1e-3f;
            evr_pixel_begin(&s, &p, t, (float)(2.0 * exp(1.0)), &sp);
            while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {
                if (nev < 16) ev[nev] = te;
                nev++;
                bad += pol != 1;
            }
            evr_pixel_end(&s, &sp);
            double expect = Lb + (La - Lb) * exp(-((double)t - 1e-7) / tau);
            if (fabs(s.l_prev - expect) > worst) worst = fabs(s.l_prev - expect);
        }
        printf("low-pass 10 Hz step response: worst error %.2g; events at", worst);
        for (k = 0; k < nev && k < 16; k++) printf(" %.5f", ev[k]);
        printf("\n");
        CHECK(worst < 2e-5);
        /* the filtered signal crosses 0.2, 0.4, 0.6, 0.8 above the start at -tau ln(1 - level)
         * and never reaches 1: four lagging events instead of five at the step */
        CHECK(nev == 4 && bad == 0);
        for (k = 0; k < nev && k < 4; k++) CHECK_NEAR(ev[k], -tau * log(1.0 - 0.2 * (k + 1)), 2e-5);
    }
    /* a dim pixel is slower: cutoff 10 * (0.1 + 20/255) / (1 + 20/255) Hz at a tenth of full brightness */
    {
        const double fc = 10.0 * (0.1 + 20.0 / 255.0) / (1.0 + 20.0 / 255.0),
                     tau = 1.0 / (2.0 * 3.14159265358979 * fc);
        evr_pixel_state s;
        evr_pixel_span sp;
        float te;
        int pol, k;
        double worst = 0;
        evr_pixel_reset(&s);
        const float Ia = (float)(0.1 * exp(-0.1)),
                    Ib = 0.1f; /* a step of 0.1 up to a tenth of full brightness */
        evr_pixel_begin(&s, &p, 0.0f, Ia, &sp);
        evr_pixel_begin(&s, &p, 1e-7f, Ib, &sp);
        while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {}
        double La = log((double)Ia), Lb = log((double)Ib);
        for (k = 1; k <= 100; k++) {
            float t = (float)k * 5e-3f;
            evr_pixel_begin(&s, &p, t, Ib, &sp);
            while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {}
            evr_pixel_end(&s, &sp);
            double expect = Lb + (La - Lb) * exp(-((double)t - 1e-7) / tau);
            if (fabs(s.l_prev - expect) / (Lb - La) > worst)
                worst = fabs(s.l_prev - expect) / (Lb - La);
        }
        printf("low-pass at a tenth of full brightness: tau %.4f s, worst relative error %.2g\n",
               tau, worst);
        CHECK(worst < 1e-3);
    }
    /* exact for a ramp: one long interval and a thousand short ones end at the same value, the
     * closed form y = L - s tau + (y0 - L0 + s tau) e^(-t / tau) */
    {
        const double tau = 1.0 / (2.0 * 3.14159265358979 * 10.0), slope = 2.0, T = 0.05;
        double ys[2];
        int c;
        for (c = 0; c < 2; c++) {
            int n = c ? 1000 : 1, k;
            evr_pixel_state s;
            evr_pixel_span sp;
            float te;
            int pol;
            evr_pixel_reset(&s);
            evr_pixel_begin(&s, &p, 0.0f, 1.5f, &sp);
            for (k = 1; k <= n; k++) {
                double t = T * k / n;
                evr_pixel_begin(&s, &p, (float)t, (float)(1.5 * exp(slope * t)), &sp);
                while (evr_pixel_next(&s, &p, &sp, &te, &pol)) {}
                evr_pixel_end(&s, &sp);
            }
            ys[c] = s.l_prev;
        }
        double L0 = log(1.5), expect = L0 + slope * T - slope * tau + slope * tau * exp(-T / tau);
        printf("low-pass ramp: one interval %.7f, 1000 intervals %.7f, closed form %.7f\n", ys[0],
               ys[1], expect);
        CHECK_NEAR(ys[0], expect, 2e-6);
        CHECK_NEAR(ys[1], expect, 2e-5);
    }
    /* the step function itself at its limits */
    CHECK(evr_lowpass_step(0.3f, 1.0f, 2.0f, 0.0f, 0.01f) == 0.3f);
    CHECK_NEAR(evr_lowpass_step(0.3f, 1.0f, 2.0f, 1e-9f, 0.01f), 0.3, 1e-6);
    CHECK_NEAR(evr_lowpass_step(0.3f, 1.0f, 2.0f, 10.0f, 0.01f), 2.0 - 1.0 * 0.01 / 10.0, 1e-6);
}

static void test_timestamps(void)
{
    evr_pixel_params p = base_params();
    int i, bad = 0, far = 0;
    /* quantized to the resolution, rounded to the nearest multiple */
    p.time_res_us = 250;
    for (i = 0; i < 100000; i++) {
        double t = 3.0 * evr_uniform(evr_hash4(1, (uint64_t)i, 0, 0));
        long long us = evr_event_time_us(&p, t, i % 7, i % 5);
        bad += us % 250 != 0;
        far += fabs((double)us - t * 1e6) > 125.0 + 1e-3;
    }
    CHECK(bad == 0 && far == 0);
    /* 1 us: plain rounding */
    p.time_res_us = 1;
    CHECK(evr_event_time_us(&p, 1.2345674, 0, 0) == 1234567);
    CHECK(evr_event_time_us(&p, 1.2345676, 0, 0) == 1234568);
    /* jitter: Gaussian with the set spread, clipped, the same for the same event */
    {
        double s1 = 0, s2 = 0, mx = 0;
        const int n = 200000;
        p.time_jitter = 20e-6f;
        for (i = 0; i < n; i++) {
            double t = 1.0 + 1e-6 * i;
            long long us = evr_event_time_us(&p, t, i % 13, 3);
            double d = (double)us - t * 1e6;
            s1 += d;
            s2 += d * d;
            if (fabs(d) > mx) mx = fabs(d);
            if (i < 100) CHECK(evr_event_time_us(&p, t, i % 13, 3) == us);
        }
        double m = s1 / n, sd = sqrt(s2 / n - m * m);
        printf(
            "timestamp jitter 20 us: mean %.3f us, sd %.3f us (with 1 us rounding), max %.1f us\n",
            m, sd, mx);
        CHECK_NEAR(m, 0.0, 0.5);
        CHECK_NEAR(sd, sqrt(400.0 + 1.0 / 12.0), 0.5);
        CHECK(mx <= 4.0 * 20.0 + 1.0);
    }
    /* a simulation with resolution and jitter on: every timestamp a multiple of the resolution */
    {
        const double R = 4.1;
        tally t;
        p = base_params();
        p.time_res_us = 100;
        p.time_jitter = 50e-6f;
        p.shot_rate = 5.0f;
        tally_init(&t, 400);
        drive(&p, 400, 0.6, 1.0 / 30.0, 10, ramp_intensity, &R, &t);
        CHECK(t.total_on + t.total_off > 6000);
        CHECK(t.not_multiple == 0);
        tally_free(&t);
    }
}

/* Everything off: the sensor model is the ideal pixel, and reports itself so. */
static void test_ideal(void)
{
    evr_pixel_params p = base_params(), q;
    CHECK(evr_pixel_params_ideal(&p));
    evr_pixel_params_at(&p, 3, 4, &q);
    CHECK(q.pos_thres == p.pos_thres && q.neg_thres == p.neg_thres && q.leak == 0.0f &&
          q.noise_rate == 0.0f);
    p.time_res_us = 2;
    CHECK(!evr_pixel_params_ideal(&p));
    p = base_params();
    p.hot_fraction = 0.1f;
    CHECK(!evr_pixel_params_ideal(&p));
    p = base_params();
    p.cutoff_hz = 1.0f;
    CHECK(!evr_pixel_params_ideal(&p));
    CHECK(sizeof(evr_pixel_state) == 36); /* 32 + the cache of change-driven sampling */
}

/* With everything off, the full model and the ideal model's own code (what the GPU's ideal
 * kernel runs) give bit-identical events, on random signals with steps, ramps and refractory
 * periods across segments. */
static void test_paths_agree(void)
{
    int trial, mismatches = 0, total = 0;
    for (trial = 0; trial < 300; trial++) {
        evr_pixel_params p = base_params();
        evr_pixel_state s[2];
        uint64_t h = evr_hash4(99, (uint64_t)trial, 0, 0);
        int seg, k, path;
        float l = 0.0f;
        p.pos_thres = 0.05f + 0.3f * evr_uniform(evr_mix64(h + 1));
        p.neg_thres = 0.05f + 0.3f * evr_uniform(evr_mix64(h + 2));
        p.refractory = (trial % 3) ? 0.0f : 2e-3f * evr_uniform(evr_mix64(h + 3));
        CHECK(evr_pixel_params_ideal(&p));
        evr_pixel_reset(&s[0]);
        evr_pixel_reset(&s[1]);
        for (seg = 0; seg < 20; seg++) {
            for (k = 0; k < 7; k++) {
                float t = ((float)k + 0.37f) / 7.0f * 0.03f;
                uint64_t r = evr_hash4(99, (uint64_t)trial, (uint64_t)seg, (uint64_t)k);
                l += (evr_uniform(r) - 0.5f) * ((r & 3) == 0 ? 3.0f : 0.3f);
                float te[2][64];
                int pol[2][64], n[2] = {0, 0};
                for (path = 0; path < 2; path++) {
                    evr_pixel_span sp;
                    float tt;
                    int pp;
                    if (!evr_pixel_begin_s(&s[path], &p, t, expf(l), &sp, path)) continue;
                    while (evr_pixel_next_s(&s[path], &p, &sp, &tt, &pp, path)) {
                        if (n[path] < 64) {
                            te[path][n[path]] = tt;
                            pol[path][n[path]] = pp;
                        }
                        n[path]++;
                    }
                    evr_pixel_end_s(&s[path], &sp, path);
                }
                total += n[0];
                if (n[0] != n[1]) mismatches++;
                for (int e = 0; e < n[0] && e < n[1] && e < 64; e++)
                    if (te[0][e] != te[1][e] || pol[0][e] != pol[1][e]) mismatches++;
            }
            evr_pixel_end_segment(&s[0], 0.03f);
            evr_pixel_end_segment(&s[1], 0.03f);
            if (s[0].ref != s[1].ref || s[0].l_prev != s[1].l_prev || s[0].t_prev != s[1].t_prev)
                mismatches++;
        }
    }
    printf("ideal and full model paths: %d events, %d mismatches\n", total, mismatches);
    CHECK(total > 10000);
    CHECK(mismatches == 0);
}

int main(void)
{
    test_ideal();
    test_paths_agree();
    test_mismatch();
    test_leak();
    test_shot();
    test_hot();
    test_refractory();
    test_lowpass();
    test_timestamps();
    return check_report("test_noise");
}
