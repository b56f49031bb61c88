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
    CHECK(evr_compare_events(ref, 4, test, 5, 100, &r, &err) == EVR_OK);
    CHECK(r.ref_on == 3 && r.ref_off == 1 && r.test_on == 4 && r.test_off == 1);
    CHECK(r.matched == 4);
    CHECK_NEAR(r.precision, 4.0 / 5.0, 1e-12);
    CHECK_NEAR(r.recall, 1.0, 1e-12);
    CHECK_NEAR(r.f1, 2 * 0.8 / 1.8, 1e-12);
    CHECK_NEAR(r.count_ratio, 5.0 / 4.0, 1e-12);
    CHECK_NEAR(r.median_dt_us, 60.0, 1e-12); /* sorted |dt|: 1, 50, 60, 100 */
    CHECK_NEAR(r.p95_dt_us, 60.0, 1e-12);    /* floor(0.95 * 3) = 2 */
    /* a tighter tolerance loses the 100 us pair and the 60 us one */
    CHECK(evr_compare_events(ref, 4, test, 5, 55, &r, &err) == EVR_OK);
    CHECK(r.matched == 2);
    /* identical streams: everything matches, correlation 1 */
    CHECK(evr_compare_events(ref, 4, ref, 4, 0, &r, &err) == EVR_OK);
    CHECK(r.matched == 4 && r.f1 == 1.0);
    CHECK_NEAR(r.pixel_count_correlation, 1.0, 1e-12);
    /* empty against empty */
    CHECK(evr_compare_events(ref, 0, test, 0, 10, &r, &err) == EVR_OK);
    CHECK(r.f1 == 0.0 || r.f1 == 1.0);
    return check_report("test_compare");
}
