/* Image-space photon mapping (src/core/photon.h, src/cpu/photon_pass.c): projection, ring
 * search, kernel, gather units, flux conservation of the pass in a closed box, determinism, the
 * photons' trails. */
#include "check.h"
#include "bsdf_env.h"
#include "core/photon.h"
#include "cpu/cpu_gi.h"
#include "cpu/photon_pass.h"

#include <embree3/rtcore.h>
#include <stdlib.h>
#include <string.h>

static void test_projection(void)
{
    evr_camera_intr c = evr_camera_intr_make(320, 240, 0.9f);
    evr_quat q = evr_quat_normalize(evr_quat_make(0.9f, 0.1f, -0.3f, 0.2f));
    evr_m34 pose;
    float r[3][3];
    int i, j;
    evr_quat_to_m33(q, r);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) pose.m[i][j] = r[i][j];
    pose.m[0][3] = 1.0f;
    pose.m[1][3] = -2.0f;
    pose.m[2][3] = 0.5f;
    evr_m34 inv = evr_m34_inverse(&pose);
    for (i = 0; i < 50; i++) {
        float px = 320.0f * (float)((i * 37) % 50) / 50.0f + 0.3f,
              py = 240.0f * (float)((i * 13) % 50) / 50.0f + 0.5f;
        float t = 0.5f + (float)i * 0.3f, qx = -1.0f, qy = -1.0f;
        int x = -1, y = -1;
        evr_ray ray = evr_camera_ray(&c, &pose, px, py);
        evr_v3 p = evr_v3_add(ray.org, evr_v3_scale(ray.dir, t));
        CHECK(evr_camera_project(&c, &inv, p, &qx, &qy));
        CHECK_NEAR(qx, px, 2e-3);
        CHECK_NEAR(qy, py, 2e-3);
        CHECK(evr_photon_pixel(&c, &inv, p, 0, &x, &y));
        CHECK(x == (int)px && y == (int)py);
        /* behind the camera: nothing */
        evr_v3 b = evr_v3_sub(ray.org, evr_v3_scale(ray.dir, t));
        CHECK(!evr_photon_pixel(&c, &inv, b, 0, &x, &y));
    }
}

static void test_rings(void)
{
    int R;
    for (R = 0; R <= 8; R++) {
        int n = 2 * R + 1, k, last = 0;
        char *seen = calloc((size_t)(n * n), 1);
        for (k = 0; k < n * n; k++) {
            int dx, dy, r = evr_ring_cell(k, &dx, &dy);
            int cheb = abs(dx) > abs(dy) ? abs(dx) : abs(dy);
            CHECK(r == cheb);
            CHECK(r >= last); /* rings in order */
            CHECK(r <= R);
            last = r;
            if (abs(dx) <= R && abs(dy) <= R) {
                CHECK(!seen[(dy + R) * n + dx + R]); /* each cell once */
                seen[(dy + R) * n + dx + R] = 1;
            }
        }
        for (k = 0; k < n * n; k++) CHECK(seen[k]);
        free(seen);
    }
}

/* The gather walks the cells in evr_ring_cell's order: the same sums bit for bit as a loop over
 * evr_ring_cell, and it stops in the ring of the cell where the count reaches the maximum. */
static void test_gather_walk(void)
{
    const int R = 5, n = 2 * R + 1;
    evr_photon_buffer b;
    evr_error err;
    int x, y, k;
    CHECK_OK(evr_photon_buffer_alloc(&b, n, n, 1, 0, &err));
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) { /* one photon per cell, every one within reach, distinct fluxes */
            evr_photon ph;
            memset(&ph, 0, sizeof ph);
            ph.p[0] = 0.01f * (float)(x - R) + 0.001f * (float)(y % 3);
            ph.p[1] = 0.01f * (float)(y - R);
            ph.n[2] = 1.0f;
            ph.flux[0] = 1.0f + 0.137f * (float)(x * n + y);
            ph.flux[1] = 3.0f / (1.0f + (float)(x + 2 * y));
            ph.flux[2] = 0.5f;
            CHECK(evr_photon_buffer_insert(&b, x, y, &ph));
        }
    const evr_v3 p = evr_v3_make(0.0013f, -0.0021f, 0.0f), nrm = evr_v3_make(0.0f, 0.0f, 1.0f);
    const float lim2 = 1.0f, s2 = 0.0025f;
    float ref[3] = {0.0f, 0.0f, 0.0f}, ref_area = 0.0f, acc[3], area;
    int stop, used;
    for (k = 0; k < n * n; k++) {
        int dx, dy;
        evr_ring_cell(k, &dx, &dy);
        evr_photon_gather_cell(&b, R + dx, R + dy, p, nrm, lim2, 0.5f, s2, ref, &ref_area);
    }
    used = evr_photon_gather_rings(&b, R, R, R, p, nrm, lim2, 0.5f, s2, 1 << 30, acc, &stop, &area);
    CHECK(used == n * n && stop == -1);
    CHECK(memcmp(acc, ref, sizeof acc) == 0); /* the same order: the same bits */
    for (k = 0; k < n * n; k++) {
        int dx, dy, ring = evr_ring_cell(k, &dx, &dy);
        used =
            evr_photon_gather_rings(&b, R, R, R, p, nrm, lim2, 0.5f, s2, k + 1, acc, &stop, &area);
        CHECK(used == k + 1 && stop == ring);
    }
    evr_photon_buffer_free(&b);
}

static void test_kernel(void)
{
    const float radii[3] = {0.01f, 1.0f, 5.0f};
    int i, x, y;
    for (i = 0; i < 3; i++) {
        float r = radii[i], h = r / 200.0f;
        double sum = 0.0;
        for (y = -200; y < 200; y++)
            for (x = -200; x < 200; x++) {
                float px = ((float)x + 0.5f) * h, py = ((float)y + 0.5f) * h;
                sum += (double)evr_gauss_kernel(px * px + py * py, r) * (double)h * (double)h;
            }
        CHECK_NEAR(sum, 1.0, 2e-3);
        CHECK(evr_gauss_kernel(r * r * 1.01f, r) == 0.0f);
        CHECK(evr_gauss_kernel(0.0f, r) > evr_gauss_kernel(0.25f * r * r, r));
    }
}

/* A plane of photons facing the camera, one per pixel with flux phi: the gather estimates the
 * irradiance phi / (pixel area on the plane). */
static void test_gather_units(void)
{
    const int w = 64, h = 64, layers = 2;
    evr_camera_intr c = evr_camera_intr_make(w, h, 0.8f);
    evr_m34 pose = evr_m34_identity(), inv = evr_m34_identity();
    evr_photon_buffer b;
    evr_error err;
    int x, y;
    const float depth = 2.0f, phi = 0.01f;
    CHECK_OK(evr_photon_buffer_alloc(&b, w, h, layers, 0, &err));
    evr_photon_buffer_clear(&b);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            evr_ray r = evr_camera_ray(&c, &pose, (float)x + 0.5f, (float)y + 0.5f);
            evr_v3 p = evr_v3_add(r.org, evr_v3_scale(r.dir, -depth / r.dir.z));
            evr_photon ph;
            int px = -1, py = -1;
            memset(&ph, 0, sizeof ph);
            ph.p[0] = p.x;
            ph.p[1] = p.y;
            ph.p[2] = p.z;
            ph.n[2] = 1.0f;
            ph.flux[0] = ph.flux[1] = ph.flux[2] = phi;
            ph.key = (uint32_t)(y * w + x);
            CHECK(evr_photon_pixel(&c, &inv, p, 0, &px, &py));
            CHECK(px == x && py == y);
            CHECK(evr_photon_buffer_insert(&b, px, py, &ph));
        }
    CHECK(*b.collisions == 0);
    float pix =
        2.0f * c.tan_half_y * depth / (float)h; /* photon spacing on the plane (near the centre) */
    evr_gather_params gp;
    gp.radius = 6.0f * pix;
    gp.max_photons = 1000;
    gp.max_window = 64;
    gp.normal_cos = 0.5f;
    float e[3];
    int used = evr_photon_gather(&b, &c, w / 2, h / 2, evr_v3_make(0.5f * pix, -0.5f * pix, -depth),
                                 evr_v3_make(0, 0, 1), depth, &gp, e);
    CHECK(used > 100);
    CHECK_NEAR(e[0] / (phi / (pix * pix)), 1.0, 0.03);
    { /* no limit (max_photons 0): the fixed-point sums give the float walk's luminance */
        evr_gather_params g0 = gp;
        evr_gather_point g;
        g.p = evr_v3_make(0.5f * pix, -0.5f * pix, -depth);
        g.n = evr_v3_make(0, 0, 1);
        g.dist = depth;
        g.k[0] = 0.3f;
        g.k[1] = 0.2f;
        g.k[2] = 0.1f;
        const float l_float = evr_gather_point_lum(&b, &c, &gp, &g, w / 2, h / 2);
        g0.max_photons = 0;
        g0.flux_scale = evr_gather_flux_scale(phi * (float)(w * h), (uint32_t)(w * h));
        const float l_fix = evr_gather_point_lum(&b, &c, &g0, &g, w / 2, h / 2);
        CHECK(l_float > 0.0f);
        CHECK_NEAR(l_fix / l_float, 1.0, 1e-5);
    }
    /* at most max_photons: the radius shrinks, the estimate stays */
    gp.max_photons = 40;
    used = evr_photon_gather(&b, &c, w / 2, h / 2, evr_v3_make(0.5f * pix, -0.5f * pix, -depth),
                             evr_v3_make(0, 0, 1), depth, &gp, e);
    CHECK(used >= 10 && used <= 80);
    CHECK_NEAR(e[0] / (phi / (pix * pix)), 1.0, 0.25);
    /* a photon facing away is skipped */
    gp.max_photons = 1000;
    used = evr_photon_gather(&b, &c, w / 2, h / 2, evr_v3_make(0, 0, -depth), evr_v3_make(0, 0, -1),
                             depth, &gp, e);
    CHECK(used == 0 && e[0] == 0.0f);
    /* half the plane (x < w / 2): at its edge the disk is half empty; the camera's view of the
     * cells (gbuf) tells the gather which half lies on the surface */
    {
        evr_photon_buffer hb;
        float e_disk[3], e_view[3];
        const float a = pix * pix; /* the area a cell covers on the plane */
        CHECK_OK(evr_photon_buffer_alloc(&hb, w, h, layers, 0, &err));
        evr_photon_buffer_clear(&hb);
        hb.gbuf = calloc((size_t)w * (size_t)h * 8, sizeof(float));
        for (y = 0; y < h; y++)
            for (x = 0; x < w / 2; x++) {
                evr_ray r = evr_camera_ray(&c, &pose, (float)x + 0.5f, (float)y + 0.5f);
                evr_v3 p = evr_v3_add(r.org, evr_v3_scale(r.dir, -depth / r.dir.z));
                evr_photon ph;
                float *g = hb.gbuf + 8 * ((size_t)y * (size_t)w + (size_t)x);
                memset(&ph, 0, sizeof ph);
                ph.p[0] = g[0] = p.x;
                ph.p[1] = g[1] = p.y;
                ph.p[2] = g[2] = p.z;
                ph.n[2] = g[5] = 1.0f;
                g[6] =
                    a; /* (2 tan / H)^2 depth^2 cos(off axis) / cos(incidence), both cosines -r.dir.z */
                ph.flux[0] = ph.flux[1] = ph.flux[2] = phi;
                evr_photon_buffer_insert(&hb, x, y, &ph);
            }
        gp.max_photons = 1000;
        evr_v3 q = evr_v3_make(-0.5f * pix, -0.5f * pix, -depth); /* the centre of pixel (31, 32) */
        float *gb = hb.gbuf;
        evr_photon_gather(&hb, &c, w / 2 - 1, h / 2, q, evr_v3_make(0, 0, 1), depth, &gp, e_view);
        hb.gbuf = NULL;
        evr_photon_gather(&hb, &c, w / 2 - 1, h / 2, q, evr_v3_make(0, 0, 1), depth, &gp, e_disk);
        CHECK_NEAR(e_view[0] / (phi / (pix * pix)), 1.0, 0.08);
        CHECK(e_disk[0] / (phi / (pix * pix)) < 0.75);
        printf("half plane edge: %.3f with the view, %.3f over the whole disk\n",
               e_view[0] / (phi / (pix * pix)), e_disk[0] / (phi / (pix * pix)));
        hb.gbuf = gb;
        evr_photon_buffer_free(&hb); /* frees gbuf too */
    }
    /* one layer: the second photon of a pixel is a collision */
    evr_photon_buffer b1;
    evr_photon ph;
    memset(&ph, 0, sizeof ph);
    CHECK_OK(evr_photon_buffer_alloc(&b1, 4, 4, 1, 0, &err));
    evr_photon_buffer_clear(&b1);
    CHECK(evr_photon_buffer_insert(&b1, 1, 2, &ph));
    CHECK(!evr_photon_buffer_insert(&b1, 1, 2, &ph));
    CHECK(*b1.collisions == 1 && b1.count[2 * 4 + 1] == 2);
    evr_photon_buffer_free(&b1);
    evr_photon_buffer_free(&b);
}

/* One hit of evr_photon_path_hit for many photons (their own random numbers) arriving along
 * -wi at the surface of e's material: the stored flux estimates the incident flux (mean 1 where
 * a photon may stay) and the flux going on has the mean of the BSDF's adjoint albedo, the
 * integral over the leaving direction wo of f(wo, wi) cos(wo) with f as direct light evaluates
 * it (evr_material_add_light on the surface seen from wo), plus the mirror's and the
 * transmission's shares, which leave along one direction. */
static void hit_energy(const bsdf_env *e, float mu, int direct, const char *what)
{
    const evr_v3 wi = view(mu);
    const evr_surface s = surface(e, wi);
    evr_photon_params pp;
    memset(&pp, 0, sizeof pp);
    pp.seed = 11;
    pp.ray_eps = 1e-5f;
    const uint32_t n = 400000;
    double stored[3] = {0, 0, 0}, out[3] = {0, 0, 0}, absorbed[3] = {0, 0, 0}, want[3] = {0, 0, 0};
    uint32_t stays = 0;
    for (uint32_t j = 0; j < n; j++) {
        evr_photon_path p;
        float st[3], ab[3];
        uint32_t key = 0;
        memset(&p, 0, sizeof p);
        p.i = p.j = j;
        p.direct = direct;
        p.pr.from_light = direct;
        p.pr.ray.org = wi;
        p.pr.ray.dir = evr_v3_scale(wi, -1.0f);
        p.pr.flux[0] = p.pr.flux[1] = p.pr.flux[2] = 1.0f;
        p.max_hits = 16;
        const int ev = evr_photon_path_hit(&p, &pp, &s, &e->mat, st, ab, &key);
        for (int c = 0; c < 3; c++) {
            absorbed[c] += ab[c];
            if (ev == EVR_PHOTON_STAY) stored[c] += st[c];
            if (ev == EVR_PHOTON_BOUNCE) out[c] += p.pr.flux[c];
        }
        stays += ev == EVR_PHOTON_STAY;
        if (ev == EVR_PHOTON_STAY) CHECK(key == j * 16u);
        if (ev == EVR_PHOTON_BOUNCE)
            CHECK(p.bounce == 1 && fabsf(evr_v3_len(p.pr.ray.dir) - 1.0f) < 1e-4f);
    }
    /* the adjoint albedo: the rough lobes by quadrature, a mirror's and transmission's shares
     * as they are (they leave at the angle they arrive) */
    const int mirror = evr_material_mirror(&s);
    const int n_mu = 400, n_phi = 240;
    for (int i = 0; i < n_mu; i++) {
        const double u0 = (double)i / n_mu, u1 = (double)(i + 1) / n_mu, um = 0.5 * (u0 + u1);
        const double c = 1.0 - um * um, dc = (1.0 - u0 * u0) - (1.0 - u1 * u1);
        const double st = sqrt(fmax(0.0, 1.0 - c * c));
        for (int k = 0; k < n_phi; k++) {
            const double phi = 6.283185307179586 * (k + 0.5) / n_phi;
            const evr_v3 wo = evr_v3_make((float)(st * cos(phi)), (float)(st * sin(phi)), (float)c);
            evr_surface so = surface(e, wo);
            const float one[3] = {1.0f, 1.0f, 1.0f};
            float acc[3] = {0.0f, 0.0f, 0.0f};
            if (mirror) so.f0[0] = so.f0[1] = so.f0[2] = so.f90 = 0.0f; /* the diffuse base alone */
            evr_material_add_light(&so, wo, wi, one, 0.0f, acc);
            for (int ch = 0; ch < 3; ch++)
                want[ch] += (double)acc[ch] / wi.z * c * dc * 6.283185307179586 / n_phi;
        }
    }
    for (int c = 0; c < 3; c++) {
        if (mirror) want[c] += s.spec_albedo[c];
        want[c] += s.transmit[c];
        stored[c] /= n;
        out[c] /= n;
        absorbed[c] /= n;
        if (fabs(out[c] - want[c]) > 0.02 * want[c])
            fprintf(stderr, "photon hit (%s, mu %.2f): channel %d goes on with %.4f, BSDF %.4f\n",
                    what, (double)mu, c, out[c], want[c]);
        CHECK(fabs(out[c] - want[c]) <= 0.02 * want[c]);
        if (direct) CHECK(stored[c] == 0.0);
        else CHECK_NEAR(stored[c], 1.0, 0.02);
        /* the bookkeeping: what the hit absorbs in expectation, by the albedo as seen */
        CHECK_NEAR(absorbed[c], 1.0 - (s.diffuse[c] + s.spec_albedo[c] + s.transmit[c]), 1e-4);
    }
    printf("photon hit (%s, mu %.2f): %.3f stayed, %.4f %.4f %.4f go on (BSDF %.4f %.4f %.4f)\n",
           what, (double)mu, (double)stays / n, out[0], out[1], out[2], want[0], want[1], want[2]);
}

static void test_hit_energy(void)
{
    static bsdf_env e;
    env_init(&e);
    e.mat.base_color[0] = 0.8f, e.mat.base_color[1] = 0.5f, e.mat.base_color[2] = 0.3f;
    e.mat.roughness = 0.6f;
    hit_energy(&e, 0.8f, 0, "rough dielectric");
    hit_energy(&e, 0.3f, 1, "rough dielectric, a light's photon");
    e.mat.metallic = 1.0f;
    e.mat.roughness = 0.35f;
    hit_energy(&e, 0.6f, 1, "rough metal");
    e.mat.metallic = 0.3f;
    hit_energy(&e, 0.6f, 0, "part metal");
    e.mat.metallic = 0.0f;
    e.mat.roughness = 0.1f; /* a mirror lobe over the diffuse base */
    hit_energy(&e, 0.5f, 0, "polished dielectric");
    e.mat.transmission = 0.6f; /* a thin wall that lets light through */
    hit_energy(&e, 0.5f, 0, "thin glass");
}

static void test_directions(void)
{
    /* cosine directions stay in the hemisphere and have mean cosine 2/3 */
    {
        evr_v3 n = evr_v3_norm(evr_v3_make(0.3f, -0.8f, 0.5f));
        double mc = 0.0;
        int i;
        for (i = 0; i < 4096; i++) {
            evr_v3 d = evr_cosine_dir(n, evr_radical_inverse((uint32_t)i + 1, 2),
                                      evr_radical_inverse((uint32_t)i + 1, 3));
            CHECK(evr_v3_dot(d, n) >= -1e-6f);
            CHECK_NEAR(evr_v3_len(d), 1.0, 1e-5);
            mc += evr_v3_dot(d, n);
        }
        CHECK_NEAR(mc / 4096.0, 2.0 / 3.0, 5e-3);
        evr_v3 m = evr_mirror_dir(evr_v3_make(1, -1, 0), evr_v3_make(0, 1, 0));
        CHECK(m.x == 1.0f && m.y == 1.0f && m.z == 0.0f);
    }
    CHECK_NEAR(evr_radical_inverse(1, 2), 0.5, 1e-7);
    CHECK_NEAR(evr_radical_inverse(5, 3), 7.0 / 9.0, 1e-6);
    CHECK(evr_photon_rand(1, 0, 17, 3) == evr_photon_rand(1, 0, 17, 3));
    CHECK(evr_photon_rand(1, 0, 17, 9) == evr_photon_rand(1, 0, 17, 9));
}

/* Emission: directions inside a spot's cone, total flux = the light's (integral of the falloff
 * for a spot, E pi R^2 for a directional light, 2 pi Le A for an emissive triangle). */
static void test_emission(void)
{
    evr_render_scene rs;
    evr_light_view l;
    evr_photon_bounds bb;
    const uint32_t n = 20000;
    uint32_t j;
    int k;
    memset(&rs, 0, sizeof rs);
    memset(&l, 0, sizeof l);
    bb.center = evr_v3_make(1, 2, 3);
    bb.radius = 2.0f;
    /* spot along -y, 0.3 / 0.5 rad */
    l.type = 1;
    l.track = -1;
    l.color[0] = l.color[1] = l.color[2] = 2.0f;
    l.pos = evr_v3_make(0, 5, 0);
    l.dir = evr_v3_make(0, -1, 0);
    l.cos_inner = cosf(0.3f);
    l.cos_outer = cosf(0.5f);
    double total = 0.0, want = 0.0;
    for (j = 0; j < n; j++) {
        float u[4];
        evr_photon_ray pr;
        for (k = 0; k < 4; k++) u[k] = evr_photon_rand(3, 0, j, k);
        evr_photon_emit_light(&rs, &l, 0.0f, bb, u, n, &pr); /* 0 at the cone's rim (zero flux) */
        CHECK(evr_v3_dot(pr.ray.dir, l.dir) >= l.cos_outer - 1e-5f);
        CHECK_NEAR(evr_v3_len(pr.ray.dir), 1.0, 1e-5);
        CHECK(pr.from_light == 1);
        total += pr.flux[0];
    }
    for (k = 0; k < 100000; k++) { /* integral of I * falloff over the cone, midpoint rule in cos */
        double cz = 1.0 - (k + 0.5) / 100000.0 * (1.0 - l.cos_outer);
        double a = (cz - l.cos_outer) / (l.cos_inner - l.cos_outer);
        a = a < 0 ? 0 : a > 1 ? 1 : a;
        want += 2.0 * 3.14159265358979 * (1.0 - l.cos_outer) / 100000.0 * a * a * l.color[0];
    }
    CHECK_NEAR(total / want, 1.0, 0.01);
    /* a point light outside the scene's sphere: only towards it, flux I * the cone's solid angle */
    l.type = 0;
    l.pos = evr_v3_make(1, 2, 13); /* 10 from the centre, radius 2 */
    total = 0.0;
    {
        float cmax = sqrtf(1.0f - 4.0f / 100.0f), fl[3];
        for (j = 0; j < n; j++) {
            float u[4];
            evr_photon_ray pr;
            for (k = 0; k < 4; k++) u[k] = evr_photon_rand(3, 4, j, k);
            CHECK(evr_photon_emit_light(&rs, &l, 0.0f, bb, u, n, &pr));
            CHECK(evr_v3_dot(pr.ray.dir, evr_v3_make(0, 0, -1)) >= cmax - 1e-5f);
            total += pr.flux[0];
        }
        CHECK_NEAR(total / (2.0 * 3.14159265358979 * (1.0 - cmax) * 2.0), 1.0, 1e-4);
        evr_photon_light_flux(&rs, &l, 0.0f, bb, fl);
        CHECK_NEAR(fl[0] / total, 1.0, 1e-4);
        l.pos = evr_v3_make(1, 2.5f, 3); /* inside: every direction */
        evr_photon_light_flux(&rs, &l, 0.0f, bb, fl);
        CHECK_NEAR(fl[0], 4.0 * 3.14159265358979 * 2.0, 1e-4);
    }
    /* directional: a disk of the bounding radius upstream, flux E pi R^2 */
    l.type = 2;
    l.dir = evr_v3_norm(evr_v3_make(1, -2, 0.5f));
    total = 0.0;
    for (j = 0; j < n; j++) {
        float u[4];
        evr_photon_ray pr;
        for (k = 0; k < 4; k++) u[k] = evr_photon_rand(3, 1, j, k);
        evr_photon_emit_light(&rs, &l, 0.0f, bb, u, n, &pr);
        evr_v3 rel = evr_v3_sub(pr.ray.org, bb.center);
        CHECK_NEAR(evr_v3_dot(rel, l.dir), -1.01 * bb.radius, 1e-4); /* upstream of the sphere */
        evr_v3 perp = evr_v3_sub(rel, evr_v3_scale(l.dir, evr_v3_dot(rel, l.dir)));
        CHECK(evr_v3_len(perp) <= bb.radius * 1.0001f);
        CHECK(pr.ray.dir.x == l.dir.x && pr.ray.dir.y == l.dir.y);
        total += pr.flux[1];
    }
    CHECK_NEAR(total / (2.0 * 3.14159265358979 * 4.0), 1.0, 1e-4);
    /* an emissive triangle, both sides: flux 2 pi Le A, points on the triangle */
    {
        static const float pos[9] = {0, 0, 0, 2, 0, 0, 0, 1, 0},
                           nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
        static const uint32_t idx[3] = {0, 1, 2};
        evr_mesh_view m;
        evr_material_params mat;
        evr_instance_view in;
        evr_photon_emitter em;
        const float cdf[1] = {1.0f};
        evr_m34 xf = evr_m34_identity();
        int up = 0;
        memset(&m, 0, sizeof m);
        memset(&mat, 0, sizeof mat);
        m.positions = pos;
        m.normals = nrm;
        m.indices = idx;
        m.num_triangles = 1;
        mat.emissive[0] = 0.5f;
        in.mesh = 0;
        in.track = 0;
        in.deform = -1;
        rs.meshes = &m;
        rs.materials = &mat;
        rs.instances = &in;
        memset(&em, 0, sizeof em);
        em.kind = 1;
        em.count = n;
        em.ntri = 1;
        em.area = 1.0f;
        total = 0.0;
        for (j = 0; j < n; j++) {
            float u[5];
            evr_photon_ray pr;
            for (k = 0; k < 5; k++) u[k] = evr_photon_rand(3, 2, j, k);
            CHECK(evr_photon_emit_surface(&rs, &em, cdf, &xf, 0.0f, u, &pr));
            CHECK(pr.from_light == 0);
            CHECK(pr.ray.org.z == 0.0f && pr.ray.org.x >= 0.0f && pr.ray.org.y >= 0.0f &&
                  pr.ray.org.x / 2.0f + pr.ray.org.y <= 1.0001f);
            up += pr.ray.dir.z > 0.0f;
            total += pr.flux[0];
        }
        CHECK_NEAR(total / (2.0 * 3.14159265358979 * 0.5 * 1.0), 1.0, 1e-4);
        CHECK(up > (int)n / 2 - 200 && up < (int)n / 2 + 200); /* both sides */
    }
}

/* ---- a closed grey box [-1, 1]^3 with a point light inside, through Embree ---- */

static float box_pos[24 * 3], box_nrm[24 * 3];
static uint32_t box_idx[36];

static void make_box(void)
{
    int f, k, v = 0, t = 0;
    for (f = 0; f < 6; f++) {
        int axis = f / 2, u = (axis + 1) % 3, w = (axis + 2) % 3;
        float s = (f % 2) ? 1.0f : -1.0f;
        for (k = 0; k < 4; k++) {
            float c[3];
            c[axis] = s;
            c[u] = (k & 1) ? 1.0f : -1.0f;
            c[w] = (k & 2) ? 1.0f : -1.0f;
            memcpy(&box_pos[3 * (v + k)], c, sizeof c);
            box_nrm[3 * (v + k)] = box_nrm[3 * (v + k) + 1] = box_nrm[3 * (v + k) + 2] = 0.0f;
            box_nrm[3 * (v + k) + axis] = -s; /* inward */
        }
        box_idx[t++] = (uint32_t)v;
        box_idx[t++] = (uint32_t)v + 1;
        box_idx[t++] = (uint32_t)v + 2;
        box_idx[t++] = (uint32_t)v + 1;
        box_idx[t++] = (uint32_t)v + 3;
        box_idx[t++] = (uint32_t)v + 2;
        v += 4;
    }
}

/* The pass's tracer over a scene of one geometry per instance (cpu/cpu_gi.h's Embree queries). */
static int tr_closest(void *user, evr_ray ray, float tnear, float tfar, float f, evr_trace_hit *hit)
{
    return evr_embree_closest1((RTCScene)user, NULL, NULL, ray, tnear, tfar, f, hit);
}

static int tr_occluded(void *user, evr_ray ray, float tnear, float tfar, float f)
{
    return evr_embree_occluded1((RTCScene)user, ray, tnear, tfar, f);
}

static int same_buffer(const evr_photon_buffer *a, const evr_photon_buffer *b)
{
    size_t npix = (size_t)a->width * (size_t)a->height, i;
    int l;
    if (memcmp(a->count, b->count, npix * sizeof *a->count) || *a->collisions != *b->collisions)
        return 0;
    for (i = 0; i < npix; i++)
        for (l = 0; l < a->layers && (uint32_t)l < a->count[i]; l++)
            if (memcmp(&a->slots[(size_t)l * npix + i], &b->slots[(size_t)l * npix + i],
                       sizeof(evr_photon)))
                return 0;
    return 1;
}

static void test_pass(void)
{
    const float rho = 0.5f;
    evr_mesh_view mesh;
    evr_material_params mat;
    evr_instance_view inst;
    evr_light_view light;
    evr_motion_key keys[2];
    int toff[2] = {0, 1}, tcnt[2] = {1, 1};
    evr_render_scene rs;
    evr_m34 id = evr_m34_identity();
    evr_error err;
    int k;
    make_box();
    memset(&mesh, 0, sizeof mesh);
    mesh.positions = box_pos;
    mesh.normals = box_nrm;
    mesh.indices = box_idx;
    mesh.num_triangles = 12;
    evr_material_defaults(&mat);
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = rho;
    mat.specular = 0.0f; /* Lambert: the albedo is rho whatever the angle */
    inst.mesh = 0;
    inst.track = 0;
    inst.deform = -1;
    memset(&light, 0, sizeof light);
    light.type = 0;
    light.track = -1;
    light.color[0] = 1.0f;
    light.color[1] = 0.5f;
    light.color[2] = 0.25f;
    light.pos = evr_v3_make(0.2f, 0.3f, -0.1f);
    keys[0] = evr_motion_key_from_matrix(&id);
    keys[1] = keys[0];
    memset(&rs, 0, sizeof rs);
    rs.meshes = &mesh;
    rs.materials = &mat;
    rs.instances = &inst;
    rs.lights = &light;
    rs.num_instances = 1;
    rs.num_lights = 1;
    rs.keys = keys;
    rs.track_offset = toff;
    rs.track_count = tcnt;
    rs.camera_track = 1;
    rs.camera_local = evr_m34_identity();
    rs.camera_local.m[2][3] = 0.9f; /* inside the box, looking at the back wall */
    rs.camera = evr_camera_intr_make(48, 40, 1.2f);
    rs.ray_eps = 1e-5f;

    RTCDevice dev = rtcNewDevice(NULL);
    RTCScene sc = rtcNewScene(dev);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 24);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 12);
    memcpy(vb, box_pos, sizeof box_pos);
    memcpy(ib, box_idx, sizeof box_idx);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(sc);

    evr_tracer tr;
    tr.user = sc;
    tr.closest = tr_closest;
    tr.occluded = tr_occluded;
    evr_photon_bounds bb;
    bb.center = evr_v3_make(0, 0, 0);
    bb.radius = 1.8f;
    evr_photon_emitters em;
    memset(&em, 0, sizeof em);
    const uint32_t N = 40000;
    CHECK_OK(evr_photon_emitters_build(&rs, 0.0f, bb, N, &em, &err));
    CHECK(em.n == 1 && em.photons == N);
    evr_photon_params pp;
    memset(&pp, 0, sizeof pp);
    pp.max_bounces = 15;
    pp.seed = 7;
    pp.threads = 1;
    pp.bounds = bb;
    pp.ray_eps = rs.ray_eps;
    evr_photon_buffer b1, b2, b3;
    evr_photon_stats s1, s2, s3;
    CHECK_OK(evr_photon_buffer_alloc(&b1, 48, 40, 4, 8, &err));
    CHECK_OK(evr_photon_buffer_alloc(&b2, 48, 40, 4, 8, &err));
    CHECK_OK(evr_photon_buffer_alloc(&b3, 48, 40, 4, 8, &err));
    CHECK_OK(evr_photon_pass(&rs, &tr, &pp, &em, &b1, &s1, NULL, &err));
    /* flux conservation: all emitted flux is absorbed (closed box), within Monte Carlo error */
    for (k = 0; k < 3; k++) {
        double want = 4.0 * 3.14159265358979 * light.color[k];
        CHECK_NEAR(s1.emitted[k] / want, 1.0, 1e-4);
        CHECK(s1.escaped[k] == 0.0);
        CHECK_NEAR((s1.absorbed[k] + s1.capped[k]) / s1.emitted[k], 1.0, 0.02);
        /* stored photons stand for the incident flux after the first hit: rho + rho^2 + ... */
        CHECK_NEAR(s1.stored[k] / (s1.emitted[k] * rho / (1.0 - rho)), 1.0, 0.03);
    }
    printf(
        "pass: %llu paths, %llu stayed, %llu visible, %llu inserted, %llu collisions; absorbed/emitted %.4f\n",
        (unsigned long long)s1.paths, (unsigned long long)s1.stored_photons,
        (unsigned long long)s1.visible, (unsigned long long)s1.inserted,
        (unsigned long long)s1.collisions, (s1.absorbed[0] + s1.capped[0]) / s1.emitted[0]);
    CHECK(s1.paths == N);
    CHECK(s1.visible > 1000 && s1.inserted + s1.collisions == s1.visible);
    /* determinism: the same photons give the same buffer, whatever the thread count */
    CHECK_OK(evr_photon_pass(&rs, &tr, &pp, &em, &b2, &s2, NULL, &err));
    pp.threads = 3;
    CHECK_OK(evr_photon_pass(&rs, &tr, &pp, &em, &b3, &s3, NULL, &err));
    CHECK(same_buffer(&b1, &b2));
    CHECK(same_buffer(&b1, &b3));
    CHECK(memcmp(s1.absorbed, s3.absorbed, sizeof s1.absorbed) == 0);
    /* a stored photon's flux: the light's power per photon times the bounces' weights over the
     * odds of staying */
    {
        size_t i, npix = (size_t)b1.width * (size_t)b1.height;
        int found = 0;
        for (i = 0; i < npix && !found; i++)
            if (b1.count[i]) {
                const evr_photon *ph = &b1.slots[i];
                CHECK(ph->flux[0] > 0.0f && ph->flux[1] > 0.0f);
                CHECK_NEAR(ph->flux[1] / ph->flux[0], 0.5,
                           1e-4); /* grey box keeps the light's colour */
                found = 1;
            }
        CHECK(found);
    }
    evr_photon_buffer_free(&b1);
    evr_photon_buffer_free(&b2);
    evr_photon_buffer_free(&b3);
    evr_photon_emitters_free(&em);
    rtcReleaseScene(sc);
    rtcReleaseDevice(dev);
}

/* A photon's trail (core/photon.h): recorded clean only while its rays miss what moves; reused
 * only when clean, when the plan allows reuse, and when no ray meets the new segment's bounds. */
static void test_trail(void)
{
    evr_skip_plan pl;
    memset(&pl, 0, sizeof pl);
    pl.cache = pl.reuse = 1;
    pl.num_boxes = 1;
    pl.lo[0][0] = 1.0f;
    pl.lo[0][1] = -1.0f;
    pl.lo[0][2] = -1.0f; /* a box at x in [1, 2] */
    pl.hi[0][0] = 2.0f;
    pl.hi[0][1] = 1.0f;
    pl.hi[0][2] = 1.0f;
    evr_photon_params pp;
    memset(&pp, 0, sizeof pp);
    pp.max_bounces = 1;
    const int len = evr_photon_trail_len(&pp);
    CHECK(len == 3);
    evr_trail_ray rays[3];
    evr_photon_trail t;
    evr_ray up = {evr_v3_make(0.0f, 0.0f, 0.0f), evr_v3_make(0.0f, 1.0f, 0.0f)};
    evr_ray toward = {evr_v3_make(0.0f, 0.0f, 0.0f), evr_v3_make(1.0f, 0.0f, 0.0f)};
    evr_photon_trail_begin(&t, &pl);
    CHECK(t.clean && t.n == 0 && t.cell == EVR_TRAIL_NONE);
    evr_photon_trail_ray(&t, rays, len, &pl, up, 5.0f);
    evr_photon_trail_ray(&t, rays, len, &pl, toward, 0.5f); /* stops short of the box */
    CHECK(t.clean && t.n == 2);
    CHECK(evr_photon_trail_reusable(&t, rays, &pl));
    /* the next segment's box covers x in [0.25, 2]: the second ray meets it */
    evr_skip_plan next = pl;
    next.lo[0][0] = 0.25f;
    CHECK(!evr_photon_trail_reusable(&t, rays, &next));
    next.lo[0][0] = 1.0f;
    next.reuse = 0; /* the camera or a light moved */
    CHECK(!evr_photon_trail_reusable(&t, rays, &next));
    /* a ray into the box (or to infinity toward it) leaves the trail unclean for good */
    evr_photon_trail_ray(&t, rays, len, &pl, toward, 1e30f);
    CHECK(!t.clean && !evr_photon_trail_reusable(&t, rays, &pl));
    /* more rays than the trail holds: unclean */
    evr_photon_trail_begin(&t, &pl);
    for (int k = 0; k < 4; k++) evr_photon_trail_ray(&t, rays, len, &pl, up, 1.0f);
    CHECK(!t.clean);
    /* a plan that may not cache (the camera moves in the segment) records no clean trail */
    evr_skip_plan moving = pl;
    moving.cache = 0;
    evr_photon_trail_begin(&t, &moving);
    CHECK(!t.clean && !evr_photon_trail_reusable(&t, rays, &pl));
}

/* The summed-area table of the cells that differ between two buffers (as the CPU pass builds it). */
static void changed_sat(const evr_photon_buffer *cur, const evr_photon_buffer *prev, uint32_t *sat)
{
    const int w = cur->width, h = cur->height;
    memset(sat, 0, (size_t)(w + 1) * (size_t)(h + 1) * sizeof *sat);
    for (int y = 0; y < h; y++) {
        uint32_t row = 0;
        for (int x = 0; x < w; x++) {
            row += !evr_photon_cell_same(cur, prev, (size_t)y * (size_t)w + (size_t)x);
            sat[(size_t)(y + 1) * (size_t)(w + 1) + (size_t)(x + 1)] =
                sat[(size_t)y * (size_t)(w + 1) + (size_t)(x + 1)] + row;
        }
    }
}

/* A gather moves only when a changed cell of its window holds, before or after, a photon it could
 * take: a change far away in space, facing away, or outside the window leaves it as it was. */
static void test_gather_moved(void)
{
    enum { N = 21 };
    const evr_camera_intr cam = evr_camera_intr_make(N, N, 0.5f * EVR_PI); /* tan(yfov / 2) = 1 */
    evr_gather_params gp = {0.2f, 64, 8, 0.5f,
                            0.0f}; /* r, max, window, normal cosine, (fixed point: unused) */
    const evr_v3 p = evr_v3_make(0.0f, 0.0f, 0.0f), nrm = evr_v3_make(0.0f, 0.0f, 1.0f);
    const float dist =
        1.0f; /* pixel size 2/21 at the point: window half size ceil(0.2 / 0.095) + 1 = 4 */
    static uint32_t sat[(N + 1) * (N + 1)];
    struct {
        float x, nz;
        int cx, in_cur;
        int moved;
        const char *what;
    } cases[] = {
        {5.0f, 1.0f, 12, 1, 0, "a photon 5 m away"},
        {0.05f, 1.0f, 12, 1, 1, "a photon within r"},
        {0.05f, -1.0f, 12, 1, 0, "a photon within r facing away"},
        {0.05f, 1.0f, 18, 1, 0, "a photon within r in a cell outside the window"},
        {0.05f, 1.0f, 12, 0, 1, "a photon within r that left"},
    };
    evr_error err;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        evr_photon_buffer cur, prev;
        CHECK_OK(evr_photon_buffer_alloc(&cur, N, N, 1, 0, &err));
        CHECK_OK(evr_photon_buffer_alloc(&prev, N, N, 1, 0, &err));
        changed_sat(&cur, &prev, sat);
        CHECK(!evr_photon_gather_moved(&cur, &prev, sat, &cam, &gp, 10, 10, p, nrm,
                                       dist)); /* nothing changed */
        evr_photon ph;
        memset(&ph, 0, sizeof ph);
        ph.p[0] = cases[c].x;
        ph.n[2] = cases[c].nz;
        ph.flux[0] = 1.0f;
        CHECK(evr_photon_buffer_insert(cases[c].in_cur ? &cur : &prev, cases[c].cx, 10, &ph));
        changed_sat(&cur, &prev, sat);
        const int moved =
            evr_photon_gather_moved(&cur, &prev, sat, &cam, &gp, 10, 10, p, nrm, dist);
        if (moved != cases[c].moved)
            fprintf(stderr, "gather moved by %s: %d, expected %d\n", cases[c].what, moved,
                    cases[c].moved);
        CHECK(moved == cases[c].moved);
        evr_photon_buffer_free(&cur);
        evr_photon_buffer_free(&prev);
    }
}

/* The cells' view: a cell adds the kernel convolved with its footprint (variance g[7]), whose
 * integral over a plane of such cells is the kernel's; a changed view whose centre lies just
 * past r but whose footprint reaches within it moves the gather, one whose footprint does not
 * leaves it as it was. */
static void test_cell_view(void)
{
    const float s2 = 0.01f, r2 = 4.0f * s2, cell = 0.01f;
    double sum = 0.0;
    for (int j = -60; j <= 60; j++)
        for (int k = -60; k <= 60; k++) {
            const float g[8] = {0, 0, 0, 0, 0, 1, cell * cell, 0.3f * cell * cell};
            const float d2 = (float)(j * j + k * k) * cell * cell;
            if (evr_cell_area_reaches(g, d2, r2)) sum += evr_cell_area_weight(g, d2, s2);
        }
    /* the kernel's integral within the disk reached: 2 pi s2 (1 - exp(-(r2 + 4 g7) / (2 s2))) */
    CHECK_NEAR(sum / (2.0 * EVR_PI * s2 * (1.0 - exp(-(r2 + 1.2 * cell * cell) / (2.0 * s2)))), 1.0,
               0.01);
    enum { N = 21 };
    const evr_camera_intr cam = evr_camera_intr_make(N, N, 0.5f * EVR_PI);
    evr_gather_params gp = {0.2f, 64, 8, 0.5f, 0.0f};
    const evr_v3 p = evr_v3_make(0.0f, 0.0f, 0.0f), nrm = evr_v3_make(0.0f, 0.0f, 1.0f);
    static uint32_t sat[(N + 1) * (N + 1)];
    evr_error err;
    for (int reach = 0; reach < 2; reach++) {
        evr_photon_buffer cur, prev;
        CHECK_OK(evr_photon_buffer_alloc(&cur, N, N, 1, 0, &err));
        CHECK_OK(evr_photon_buffer_alloc(&prev, N, N, 1, 0, &err));
        cur.gbuf = calloc((size_t)N * N * 8, sizeof(float));
        prev.gbuf = calloc((size_t)N * N * 8, sizeof(float));
        float *gc = cur.gbuf + 8 * (10 * N + 12), *gpv = prev.gbuf + 8 * (10 * N + 12);
        gc[0] = gpv[0] = 0.21f; /* just past r = 0.2 */
        gc[5] = gpv[5] = 1.0f;
        gc[6] = 0.01f;
        gpv[6] = 0.02f;                         /* the view changed */
        gc[7] = gpv[7] = reach ? 0.002f : 0.0f; /* 4 g7 = 0.008 > 0.21^2 - 0.2^2 = 0.0041 */
        changed_sat(&cur, &prev, sat);
        CHECK(evr_photon_gather_moved(&cur, &prev, sat, &cam, &gp, 10, 10, p, nrm, 1.0f) == reach);
        evr_photon_buffer_free(&cur);
        evr_photon_buffer_free(&prev);
    }
}

static uint64_t rng_next(uint64_t *s) { return evr_mix64(++*s); }
static float rng_uniform(uint64_t *s) { return evr_uniform(rng_next(s)); }

/* The fixed-point sums (max_photons 0): a buffer's sums are another's plus the changed cells'
 * terms minus their old ones, bit for bit, for gathers all over the image; the luminance from
 * sums made either way is the same, and is evr_gather_point_lum's. */
static void test_gather_delta(void)
{
    enum { W = 48, H = 40, LAYERS = 3 };
    const evr_camera_intr cam = evr_camera_intr_make(W, H, 0.8f);
    const evr_m34 pose = evr_m34_identity();
    evr_gather_params gp = {0.15f, 0, 6, 0.5f, 0.0f};
    evr_photon_buffer a, b;
    evr_error err;
    static uint32_t sat[(W + 3) * (H + 3)], before[(W + 3) * (H + 2)], base[H + 3],
        xs[(W + 2) * (H + 2)];
    uint64_t rng = 12345;
    int changed = 0;
    gp.flux_scale = evr_gather_flux_scale(1.0f, 1000u);
    CHECK_OK(evr_photon_buffer_alloc(&a, W, H, LAYERS, 1, &err));
    CHECK_OK(evr_photon_buffer_alloc(&b, W, H, LAYERS, 1, &err));
    evr_photon_buffer_clear(&a);
    evr_photon_buffer_clear(&b);
    a.gbuf = calloc((size_t)a.width * (size_t)a.height * 8, sizeof(float));
    b.gbuf = calloc((size_t)b.width * (size_t)b.height * 8, sizeof(float));
    /* photons on the plane z = -2 (a wall) and z = -1.5 (a step), one to three a cell; b: a's,
     * with a tenth of the cells given other photons or another view */
    for (int y = -1; y <= H; y++)
        for (int x = -1; x <= W; x++) {
            const size_t i = (size_t)(y + 1) * (size_t)a.width + (size_t)(x + 1);
            const int n = 1 + (int)(rng_next(&rng) % 3u), moved = rng_uniform(&rng) < 0.1f;
            evr_ray r = evr_camera_ray(&cam, &pose, (float)x + 0.5f, (float)y + 0.5f);
            const float depth = x < W / 2 ? 2.0f : 1.5f;
            evr_v3 q = evr_v3_add(r.org, evr_v3_scale(r.dir, -depth / r.dir.z));
            for (int k = 0; k < 8; k++)
                a.gbuf[8 * i + (size_t)k] = b.gbuf[8 * i + (size_t)k] = 0.0f;
            a.gbuf[8 * i] = q.x;
            a.gbuf[8 * i + 1] = q.y;
            a.gbuf[8 * i + 2] = q.z;
            a.gbuf[8 * i + 5] = 1.0f;
            a.gbuf[8 * i + 6] = 0.002f;
            for (int k = 0; k < 8; k++) b.gbuf[8 * i + (size_t)k] = a.gbuf[8 * i + (size_t)k];
            if (moved && (rng_next(&rng) & 1u)) b.gbuf[8 * i + 6] = 0.003f;
            for (int l = 0; l < n; l++) {
                evr_photon ph;
                memset(&ph, 0, sizeof ph);
                ph.p[0] = q.x + 0.01f * (rng_uniform(&rng) - 0.5f);
                ph.p[1] = q.y + 0.01f * (rng_uniform(&rng) - 0.5f);
                ph.p[2] = q.z;
                ph.n[2] = 1.0f;
                ph.flux[0] = 0.001f * rng_uniform(&rng);
                ph.flux[1] = 0.002f * rng_uniform(&rng);
                ph.flux[2] = 0.0005f;
                ph.key = (uint32_t)l;
                CHECK(evr_photon_buffer_insert(&a, x, y, &ph));
                if (moved && l == 0) ph.flux[1] *= 3.0f;
                if (!(moved && l == n - 1 && n > 1)) CHECK(evr_photon_buffer_insert(&b, x, y, &ph));
            }
        }
    changed_sat(&b, &a, sat);
    const evr_changed_cells ch =
        evr_changed_cells_from_sat(sat, b.width, b.height, before, base, xs);
    changed = (int)base[b.height];
    CHECK(changed == (int)sat[(size_t)b.height * (size_t)(b.width + 1) + (size_t)b.width]);
    CHECK(changed > (W * H) / 20);
    int checked = 0, nonzero = 0;
    for (int y = 0; y < H; y += 3)
        for (int x = 0; x < W; x += 2) {
            evr_ray r = evr_camera_ray(&cam, &pose, (float)x + 0.5f, (float)y + 0.5f);
            const float depth = x < W / 2 ? 2.0f : 1.5f;
            evr_gather_point g;
            g.p = evr_v3_add(r.org, evr_v3_scale(r.dir, -depth / r.dir.z));
            g.n = evr_v3_make(0.0f, 0.0f, 1.0f);
            g.dist = evr_v3_len(g.p);
            g.k[0] = 0.2f;
            g.k[1] = 0.1f;
            g.k[2] = 0.05f;
            evr_gather_sum sa, sb, sd;
            evr_gather_point_sum(&a, &cam, &gp, &g, x, y, &sa);
            evr_gather_point_sum(&b, &cam, &gp, &g, x, y, &sb);
            sd = sa;
            evr_gather_point_delta(&b, &a, &ch, &cam, &gp, &g, x, y, &sd);
            CHECK(memcmp(&sd, &sb, sizeof sb) == 0);
            const float l = evr_gather_sum_lum(&b, &cam, &gp, &g, x, y, &sd);
            CHECK(l == evr_gather_point_lum(&b, &cam, &gp, &g, x, y));
            nonzero += memcmp(&sa, &sb, sizeof sa) != 0;
            checked++;
        }
    printf(
        "fixed-point gathers: %d checked, %d changed by the %d changed cells, every one equal to a fresh gather\n",
        checked, nonzero, changed);
    CHECK(nonzero > checked / 2);
    evr_photon_buffer_free(&a);
    evr_photon_buffer_free(&b);
}

/* The blurred estimate (core/photon_blur.h) on a 16 x 8 buffer whose cells see points 0.1 apart on
 * the plane z = 0 seen from 1 away: the left half instance 0 with a noisy irradiance, one column
 * of it turned to face +x (another surface), the right half instance 1 at 3 over cells of two
 * footprint areas. Each cell holds one photon of its irradiance times its area, plus two it must
 * not count (off the plane, facing away). The blur smooths the left half around its mean, keeps
 * the turned column and the right half apart, and gives the right half its density whatever the
 * areas; a lookup takes the cell's estimate, its like neighbours' mean at an outline, the mean of
 * what is around, or nothing; a sample seen at one pass only takes that pass's estimate at both. */
static void test_blur(void)
{
    enum { W = 16, H = 8, L = 3 };
    evr_photon_buffer b, none;
    static float gbuf[W * H * 8], e[W * H * 3], work[2][W * H * EVR_BLUR_CH];
    static evr_photon slots[L * W * H];
    static uint32_t count[W * H];
    static int inst[W * H], inst_none[W * H];
    int x, y, k;
    /* a camera whose pixel spans 0.1 at distance 1: steps 1, 2, 4 for sigma 0.4 */
    evr_camera_intr cam = evr_camera_intr_make(W, H, 2.0f * atanf(0.05f * (float)H));
    const evr_v3 org = evr_v3_make(0.0f, 0.0f, 1.0f);
    evr_gather_params gp;
    memset(&gp, 0, sizeof gp);
    gp.radius = 0.1f;
    gp.normal_cos = 0.7f;
    memset(&b, 0, sizeof b);
    b.width = W;
    b.height = H;
    b.layers = L;
    b.slots = slots;
    b.count = count;
    b.gbuf = gbuf;
    b.view_inst = inst;
    b.blur = e;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            const int i = y * W + x, turned = x == 3;
            const float irr = turned ? 10.0f : x < W / 2 ? ((x + y) % 2 ? 0.5f : 1.5f) : 3.0f;
            float *g = gbuf + 8 * i;
            g[0] =
                0.1f * (float)x; /* every cell at distance 1: positions enter through differences */
            g[1] = 0.1f * (float)y;
            g[3] = turned ? 1.0f : 0.0f;
            g[5] = turned ? 0.0f : 1.0f;
            g[6] = x >= W / 2 && x % 2 ? 0.03f : 0.01f;
            inst[i] = x < W / 2 ? 0 : 1;
            inst_none[i] = -1;
            count[i] = L;
            for (int l = 0; l < L; l++) {
                evr_photon *ph = &slots[l * W * H + i];
                memset(ph, 0, sizeof *ph);
                for (int c = 0; c < 3; c++) {
                    ph->p[c] =
                        g[c] + (l == 1 ? 0.5f * g[3 + c] : 0.0f); /* layer 1: off the plane */
                    ph->n[c] = l == 2 ? -g[3 + c] : g[3 + c];     /* layer 2: facing away */
                    ph->flux[c] = irr * g[6];
                }
            }
        }
    const float pix = evr_camera_pixel_size(&cam, 1.0f);
    CHECK_NEAR(pix, 0.1f, 1e-4);
    CHECK(evr_blur_steps(0.4f, 0.1f) == 3); /* steps 1, 2, 4: taps up to 8 cells out, 2 sigma */
    CHECK(evr_blur_steps(0.05f, 0.1f) == 1 && evr_blur_steps(1e6f, 0.1f) == EVR_BLUR_MAX_STEPS);
    for (int i = 0; i < W * H; i++) {
        evr_blur_cell_splat(&b, &gp, (size_t)i, work[0] + EVR_BLUR_CH * i);
        CHECK(work[0][EVR_BLUR_CH * i + 3] == gbuf[8 * i + 6]);
        CHECK(work[0][EVR_BLUR_CH * i] == slots[i].flux[0]); /* the first photon alone */
    }
    for (k = 0; k < 3; k++)
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x++)
                evr_blur_cell(&b, &cam, org, 0.4f, work[k % 2], work[(k + 1) % 2], x, y, k);
    for (int i = 0; i < W * H; i++) evr_blur_cell_finish(&b, work[1], (size_t)i);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            const float v = e[3 * (y * W + x)];
            if (x == 3) CHECK_NEAR(v, 10.0f, 1e-4);
            else if (x < W / 2) CHECK(v > 0.9f && v < 1.1f);
            else CHECK_NEAR(v, 3.0f, 1e-5);
        }
    float out[3], es[3], ee[3];
    const evr_v3 up = evr_v3_make(0.0f, 0.0f, 1.0f);
    CHECK(evr_blur_lookup(&b, 10, 4, 1, up, out) == EVR_BLUR_LIKE && out[0] == e[3 * (4 * W + 10)]);
    /* instance 1 seen through cell (8, 4)'s left neighbour: the mean of its like neighbours */
    CHECK(evr_blur_lookup(&b, 7, 4, 1, up, out) == EVR_BLUR_LIKE);
    CHECK_NEAR(out[0], 3.0f, 1e-5);
    /* the turned column from a cell of the plane: its own cell only faces +x */
    CHECK(evr_blur_lookup(&b, 3, 4, 0, evr_v3_make(1.0f, 0.0f, 0.0f), out) == EVR_BLUR_LIKE);
    CHECK_NEAR(out[0], 10.0f, 1e-4);
    /* nothing of instance 1 around: the mean of the nine */
    CHECK(evr_blur_lookup(&b, 1, 4, 1, up, out) == EVR_BLUR_NEAR && out[0] > 0.5f && out[0] < 1.5f);
    none = b;
    none.view_inst = inst_none;
    CHECK(evr_blur_lookup(&none, 1, 4, 0, up, out) == EVR_BLUR_NONE && out[0] == 0.0f);
    /* seen at the end's pass only: the end's estimate at both */
    evr_blur_ends(&none, &b, 10, 4, 1, up, es, ee);
    CHECK(es[0] == ee[0] && ee[0] == e[3 * (4 * W + 10)]);
    CHECK(evr_blur_cell_same(&b, &b, 5) && !evr_blur_cell_same(&b, &none, 5));
}

int main(void)
{
    test_projection();
    test_rings();
    test_gather_walk();
    test_kernel();
    test_gather_units();
    test_directions();
    test_hit_energy();
    test_emission();
    test_pass();
    test_trail();
    test_gather_moved();
    test_gather_delta();
    test_cell_view();
    test_blur();
    return check_report("test_photon");
}
