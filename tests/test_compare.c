/* evr_compare_events on hand-made streams with known answers. */
#include "check.h"
#include "compare.h"

int main(void)
{
    /* reference: pixel (1,0) ON at 100, 200, 300; pixel (0,1) OFF at 1000 */
    evr_event ref[4] = {
        {100, 1, 0, 1, 0}, {200, 1, 0, 1, 0}, {300, 1, 0, 1, 0}, {1000, 0, 1, 0, 0}};
    /* test: 150 matches 100 or 200 (greedy in time order: 100), 260 matches 200 (dt 60),
     * 900 (OFF, same pixel) within 100 of 1000, an ON at (0,1) matches nothing, 301 matches 300 */
    evr_event test[5] = {{150, 1, 0, 1, 0},
                         {260, 1, 0, 1, 0},
                         {301, 1, 0, 1, 0},
                         {900, 0, 1, 0, 0},
                         {950, 0, 1, 1, 0}};
    evr_compare_result r;
    evr_error err;
    CHECK(evr_compare_events(ref, 4, test, 5, 100, 0.0, &r, &err) == EVR_OK);
    CHECK(r.ref_on == 3 && r.ref_off == 1 && r.test_on == 4 && r.test_off == 1);
    CHECK(r.matched == 4);
    CHECK_NEAR(r.precision, 4.0 / 5.0, 1e-12);
    CHECK_NEAR(r.recall, 1.0, 1e-12);
    CHECK_NEAR(r.f1, 2 * 0.8 / 1.8, 1e-12);
    CHECK_NEAR(r.count_ratio, 5.0 / 4.0, 1e-12);
    CHECK_NEAR(r.median_dt_us, 60.0, 1e-12); /* sorted |dt|: 1, 50, 60, 100 */
    CHECK_NEAR(r.p95_dt_us, 60.0, 1e-12);    /* floor(0.95 * 3) = 2 */
    /* a tighter tolerance loses the 100 us pair and the 60 us one */
    CHECK(evr_compare_events(ref, 4, test, 5, 55, 0.0, &r, &err) == EVR_OK);
    CHECK(r.matched == 2);
    /* identical streams: everything matches, correlation 1 */
    CHECK(evr_compare_events(ref, 4, ref, 4, 0, 0.0, &r, &err) == EVR_OK);
    CHECK(r.matched == 4 && r.f1 == 1.0);
    CHECK_NEAR(r.pixel_count_correlation, 1.0, 1e-12);
    /* the level tolerance: a slow pixel's events (gaps of 100 ms) placed 8 ms off match at a
     * tenth of the gap, not at 1 ms; a fast pixel's (gaps of 1 ms) keep the fixed 1 ms, so
     * 1.2 ms off misses there either way. The first event of a group takes the gap to the next. */
    {
        evr_event slow_ref[5] = {{0, 2, 0, 1, 0},
                                 {100000, 2, 0, 1, 0},
                                 {200000, 2, 0, 1, 0},
                                 {200500, 3, 0, 0, 0},
                                 {201500, 3, 0, 0, 0}};
        evr_event slow_test[5] = {{8000, 2, 0, 1, 0},
                                  {108000, 2, 0, 1, 0},
                                  {189000, 2, 0, 1, 0},
                                  {202700, 3, 0, 0, 0},
                                  {203900, 3, 0, 0, 0}};
        CHECK(evr_compare_events(slow_ref, 5, slow_test, 5, 1000, 0.0, &r, &err) == EVR_OK);
        CHECK(r.matched == 0);
        CHECK(evr_compare_events(slow_ref, 5, slow_test, 5, 1000, 0.1, &r, &err) == EVR_OK);
        /* 8, 8 and 11 ms off the slow pixel's: the first two within 10 ms, the third not; the
         * fast pixel's, 1.2 ms off, are not within max(1 ms, 0.1 ms) */
        CHECK(r.matched == 2);
        CHECK(evr_compare_events(slow_ref, 5, slow_test, 5, 1000, 0.15, &r, &err) == EVR_OK);
        CHECK(r.matched == 3);
    }
    /* empty against empty */
    CHECK(evr_compare_events(ref, 0, test, 0, 10, 0.0, &r, &err) == EVR_OK);
    CHECK(r.f1 == 0.0 || r.f1 == 1.0);
    return check_report("test_compare");
}
