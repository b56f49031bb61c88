/* Motion keys: decomposition round trip, shortest-arc slerp, and that our interpolation (used by
 * the camera and the GPU) is exactly the one Embree applies to motion-blurred instances. */
#include "check.h"
#include "core/motion.h"
#include "core/rng.h"

#include <embree3/rtcore.h>
#include <string.h>

static float rnd(uint64_t *c) { return evr_uniform(evr_hash4(99, (*c)++, 0, 0)) * 2.0f - 1.0f; }

static evr_motion_key random_key(uint64_t *c)
{
    evr_motion_key k;
    k.scale[0] = 0.5f + rnd(c) * 0.3f + 0.5f;
    k.scale[1] = 0.5f + rnd(c) * 0.3f + 0.5f;
    k.scale[2] = 0.5f + rnd(c) * 0.3f + 0.5f;
    k.skew[0] = 0.2f * rnd(c);
    k.skew[1] = 0.2f * rnd(c);
    k.skew[2] = 0.2f * rnd(c);
    k.rot = evr_quat_normalize(evr_quat_make(rnd(c), rnd(c), rnd(c), rnd(c)));
    k.trans = evr_v3_make(3 * rnd(c), 3 * rnd(c), 3 * rnd(c));
    return k;
}

static double mat_diff(const evr_m34 *a, const evr_m34 *b)
{
    double d = 0;
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++) d = fmax(d, fabs((double)a->m[i][j] - (double)b->m[i][j]));
    return d;
}

int main(void)
{
    uint64_t c = 1;
    int i, j;

    /* matrix -> key -> matrix */
    for (i = 0; i < 200; i++) {
        evr_motion_key k = random_key(&c);
        evr_m34 m = evr_motion_key_matrix(&k);
        evr_motion_key k2 = evr_motion_key_from_matrix(&m);
        evr_m34 m2 = evr_motion_key_matrix(&k2);
        CHECK(mat_diff(&m, &m2) < 1e-5);
    }
    /* a mirroring matrix keeps a proper rotation and a negative scale */
    {
        evr_m34 m = evr_m34_identity();
        m.m[0][0] = -2.0f;
        evr_motion_key k = evr_motion_key_from_matrix(&m);
        evr_m34 m2 = evr_motion_key_matrix(&k);
        CHECK(mat_diff(&m, &m2) < 1e-6);
    }
    /* slerp takes the shortest arc: q and -q are the same rotation, so nothing turns */
    {
        evr_quat a = evr_quat_normalize(evr_quat_make(0.3f, 0.5f, -0.2f, 0.7f));
        evr_quat b = evr_quat_make(-a.w, -a.x, -a.y, -a.z);
        evr_quat m = evr_quat_slerp(a, b, 0.5f);
        CHECK(fabsf(evr_quat_dot(a, m)) > 0.99999f);
        /* 90 degrees about Z, halfway is 45 degrees */
        evr_quat z0 = evr_quat_make(1, 0, 0, 0),
                 z90 = evr_quat_make(cosf(0.7853982f), 0, 0, sinf(0.7853982f));
        evr_quat h = evr_quat_slerp(z0, z90, 0.5f);
        CHECK_NEAR(2 * acosf(h.w), 0.7853982, 1e-5);
    }

    /* our interpolation equals Embree's on instances with quaternion time steps */
    RTCDevice dev = rtcNewDevice(NULL);
    CHECK(dev != NULL);
    RTCScene mesh = rtcNewScene(dev);
    RTCGeometry tri = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(tri, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 3);
    unsigned *ib = rtcSetNewGeometryBuffer(tri, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 1);
    float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    unsigned idx[3] = {0, 1, 2};
    memcpy(vb, v, sizeof v);
    memcpy(ib, idx, sizeof idx);
    rtcCommitGeometry(tri);
    rtcAttachGeometry(mesh, tri);
    rtcReleaseGeometry(tri);
    rtcCommitScene(mesh);
    for (i = 0; i < 20; i++) {
        evr_motion_key keys[5];
        int n = 2 + i % 4, s;
        RTCGeometry inst = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, mesh);
        rtcSetGeometryTimeStepCount(inst, (unsigned)n);
        for (s = 0; s < n; s++) {
            keys[s] = random_key(&c);
            /* neighbouring keys within 120 degrees and in the same hemisphere, as the scene code makes them */
            if (s > 0) {
                keys[s].rot = evr_quat_slerp(keys[s - 1].rot, keys[s].rot, 0.3f);
                if (evr_quat_dot(keys[s - 1].rot, keys[s].rot) < 0) {
                    evr_quat q = keys[s].rot;
                    keys[s].rot = evr_quat_make(-q.w, -q.x, -q.y, -q.z);
                }
            }
            struct RTCQuaternionDecomposition q;
            rtcInitQuaternionDecomposition(&q);
            q.scale_x = keys[s].scale[0];
            q.scale_y = keys[s].scale[1];
            q.scale_z = keys[s].scale[2];
            q.skew_xy = keys[s].skew[0];
            q.skew_xz = keys[s].skew[1];
            q.skew_yz = keys[s].skew[2];
            q.quaternion_r = keys[s].rot.w;
            q.quaternion_i = keys[s].rot.x;
            q.quaternion_j = keys[s].rot.y;
            q.quaternion_k = keys[s].rot.z;
            q.translation_x = keys[s].trans.x;
            q.translation_y = keys[s].trans.y;
            q.translation_z = keys[s].trans.z;
            rtcSetGeometryTransformQuaternion(inst, (unsigned)s, &q);
        }
        rtcCommitGeometry(inst);
        evr_motion_track tr = {keys, n};
        for (j = 0; j <= 16; j++) {
            float f = (float)j / 16.0f;
            float x[12];
            rtcGetGeometryTransform(inst, f, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, x);
            evr_m34 e, ours = evr_motion_eval(tr, f);
            memcpy(e.m, x, sizeof x);
            double d = mat_diff(&e, &ours);
            if (d > 2e-5) fprintf(stderr, "key set %d f=%g: differs from Embree by %g\n", i, f, d);
            CHECK(d < 2e-5);
        }
        rtcReleaseGeometry(inst);
    }
    rtcReleaseScene(mesh);
    rtcReleaseDevice(dev);
    return check_report("test_motion");
}
