/* Camera paths: see camera_path.h. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "scene/camera_path.h"

enum {
    P_PERIOD = 1,
    P_SPEED = 2,
    P_RATE = 4,
    P_AMP = 8,
    P_TREMOR = 16,
    P_MOVE = 32,
    P_CENTRE = 64,
    P_AXIS = 128,
    P_DIR = 256,
    P_SEED = 512
};

#define FAIL(...)                                         \
    do {                                                  \
        snprintf(err->msg, sizeof err->msg, __VA_ARGS__); \
        return EVR_ERR_ARG;                               \
    } while (0)

static const struct {
    const char *name;
    evr_motion_kind kind;
    unsigned params;
} kinds[] = {
    {"orbit", EVR_MOTION_ORBIT, P_PERIOD | P_CENTRE | P_AXIS},
    {"dolly", EVR_MOTION_DOLLY, P_SPEED | P_DIR},
    {"fly", EVR_MOTION_DOLLY, P_SPEED | P_DIR},
    {"pan", EVR_MOTION_PAN, P_RATE | P_AMP | P_PERIOD},
    {"tilt", EVR_MOTION_TILT, P_RATE | P_AMP | P_PERIOD},
    {"shake", EVR_MOTION_SHAKE, P_AMP | P_TREMOR | P_MOVE | P_SEED},
};
#define NUM_KINDS ((int)(sizeof kinds / sizeof kinds[0]))

static const struct {
    const char *name;
    unsigned bit;
} params[] = {{"period", P_PERIOD}, {"speed", P_SPEED}, {"rate", P_RATE},     {"amp", P_AMP},
              {"tremor", P_TREMOR}, {"move", P_MOVE},   {"centre", P_CENTRE}, {"center", P_CENTRE},
              {"axis", P_AXIS},     {"dir", P_DIR},     {"seed", P_SEED}};
#define NUM_PARAMS ((int)(sizeof params / sizeof params[0]))

#define KIND_LIST "orbit, dolly, fly, pan, tilt, shake, or tum:FILE"

/* ---- parsing ---- */

static int parse_number(const char *s, size_t len, double *v)
{
    char buf[64], *end;
    if (len == 0 || len >= sizeof buf) return 0;
    memcpy(buf, s, len);
    buf[len] = 0;
    errno = 0;
    *v = strtod(buf, &end);
    return end != buf && !*end && !errno && isfinite(*v);
}

static int parse_vector(const char *s, size_t len, double v[3])
{
    size_t i = 0;
    for (int k = 0; k < 3; k++) {
        size_t j = i;
        while (j < len && s[j] != ',') j++;
        if (!parse_number(s + i, j - i, &v[k])) return 0;
        if (k < 2 && j >= len) return 0;
        i = j + 1;
    }
    return i == len + 1;
}

static void param_names(unsigned allowed, char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = 0;
    for (int i = 0; i < NUM_PARAMS; i++)
        if ((allowed & params[i].bit) && strcmp(params[i].name, "center"))
            len += (size_t)snprintf(buf + len, len < n ? n - len : 0, "%s%s", len ? ", " : "",
                                    params[i].name);
}

/* One parameter "name=value" of motion m (kind name kn, allowed parameters). */
static evr_status parse_param(evr_path_motion *m, const char *kn, unsigned allowed, const char *s,
                              size_t len, evr_error *err)
{
    const char *eq = memchr(s, '=', len);
    char names[128];
    int i;
    size_t nl = eq ? (size_t)(eq - s) : len;
    for (i = 0; i < NUM_PARAMS; i++)
        if (strlen(params[i].name) == nl && !strncmp(params[i].name, s, nl)) break;
    param_names(allowed, names, sizeof names);
    if (i == NUM_PARAMS || !(allowed & params[i].bit))
        FAIL("camera path %s: unknown parameter '%.*s' (%s)", kn, (int)nl, s, names);
    if (!eq)
        FAIL("camera path %s: parameter '%.*s' needs a value (%.*s=...)", kn, (int)nl, s, (int)nl,
             s);
    const char *v = eq + 1;
    const size_t vl = len - nl - 1;
    const unsigned bit = params[i].bit;
    double x = 0.0, *vec = bit == P_CENTRE ? m->centre : bit == P_AXIS ? m->axis : m->dir;
    if (bit == P_CENTRE || bit == P_AXIS || bit == P_DIR) {
        if (!parse_vector(v, vl, vec))
            FAIL("camera path %s: %s expects X,Y,Z, got '%.*s'", kn, params[i].name, (int)vl, v);
        if (bit != P_CENTRE && vec[0] == 0.0 && vec[1] == 0.0 && vec[2] == 0.0)
            FAIL("camera path %s: %s must not be zero", kn, params[i].name);
    } else {
        if (!parse_number(v, vl, &x))
            FAIL("camera path %s: %s expects a number, got '%.*s'", kn, params[i].name, (int)vl, v);
        switch (bit) {
        case P_PERIOD:
            if (x == 0.0) FAIL("camera path %s: period must not be 0 seconds", kn);
            if (m->kind != EVR_MOTION_ORBIT && x < 0.0)
                FAIL("camera path %s: period must be a positive number of seconds (got %g)", kn, x);
            m->period = x;
            break;
        case P_SPEED: m->speed = x; break;
        case P_RATE: m->rate = x; break;
        case P_AMP:
        case P_TREMOR:
        case P_MOVE:
            if (x < 0.0) FAIL("camera path %s: %s must be >= 0 (got %g)", kn, params[i].name, x);
            if (bit == P_AMP) m->amp = x;
            else if (bit == P_TREMOR) m->tremor = x;
            else m->move = x;
            break;
        case P_SEED:
            if (x < 0.0 || x != floor(x) || x > 9007199254740992.0)
                FAIL("camera path %s: seed expects a non-negative integer, got '%.*s'", kn, (int)vl,
                     v);
            m->seed = (uint64_t)x;
            break;
        default: break;
        }
    }
    m->given |= bit;
    return EVR_OK;
}

static evr_status read_tum(const char *path, evr_path_motion *m, evr_error *err);

/* One motion of the path (s, len: its text). */
static evr_status parse_motion(const char *s, size_t len, int read_files, evr_path_motion *m,
                               evr_error *err)
{
    char file[4096];
    const char *colon = memchr(s, ':', len);
    size_t kl = colon ? (size_t)(colon - s) : len;
    int k;
    memset(m, 0, sizeof *m);
    if (len == 0) FAIL("camera path: an empty motion (between '+' signs, or at an end)");
    for (k = 0; k < NUM_KINDS; k++)
        if (strlen(kinds[k].name) == kl && !strncmp(kinds[k].name, s, kl)) break;
    if (k == NUM_KINDS) { /* a trajectory file: tum:FILE, or a name that looks like a file */
        const int tagged = kl == 3 && !strncmp(s, "tum", 3);
        const char *f = tagged ? colon + 1 : s;
        const size_t fl = tagged ? len - 4 : len;
        if (!tagged && !memchr(s, '.', len) && !memchr(s, '/', len))
            FAIL("camera path: unknown kind '%.*s' (" KIND_LIST ")", (int)kl, s);
        if (fl == 0) FAIL("camera path: tum: needs a file name (tum:FILE)");
        if (fl >= sizeof file) FAIL("camera path: file name too long");
        memcpy(file, f, fl);
        file[fl] = 0;
        m->kind = EVR_MOTION_TUM;
        return read_files ? read_tum(file, m, err) : EVR_OK;
    }
    m->kind = kinds[k].kind;
    m->period = m->kind == EVR_MOTION_ORBIT ? 10.0 : 4.0;
    m->rate = 10.0;
    m->amp = m->kind == EVR_MOTION_SHAKE ? 0.25 : 10.0;
    m->tremor = 0.02;
    m->axis[1] = 1.0;
    size_t i = kl;
    while (i < len) { /* ":name=value" */
        size_t j = ++i;
        while (j < len && s[j] != ':') j++;
        evr_status st = parse_param(m, kinds[k].name, kinds[k].params, s + i, j - i, err);
        if (st != EVR_OK) return st;
        i = j;
    }
    if ((m->kind == EVR_MOTION_PAN || m->kind == EVR_MOTION_TILT) && (m->given & P_RATE) &&
        (m->given & (P_AMP | P_PERIOD)))
        FAIL("camera path %s: rate (a steady turn) or amp and period (a sweep), not both",
             kinds[k].name);
    return EVR_OK;
}

evr_status evr_camera_path_parse(const char *spec, int read_files, evr_camera_path *p,
                                 evr_error *err)
{
    memset(p, 0, sizeof *p);
    if (!spec || !spec[0]) FAIL("camera path: empty (" KIND_LIST ")");
    const size_t len = strlen(spec);
    size_t i = 0;
    while (i <= len) {
        size_t j = i;
        while (j < len && spec[j] != '+') j++;
        if (p->num == EVR_PATH_MAX_MOTIONS) {
            evr_camera_path_free(p);
            FAIL("camera path: more than %d motions", EVR_PATH_MAX_MOTIONS);
        }
        evr_status st = parse_motion(spec + i, j - i, read_files, &p->m[p->num], err);
        p->num++;
        if (st == EVR_OK && p->m[p->num - 1].kind == EVR_MOTION_TUM && p->num > 1) {
            snprintf(err->msg, sizeof err->msg,
                     "camera path: a trajectory file sets the whole pose, so it comes first");
            st = EVR_ERR_ARG;
        }
        if (st != EVR_OK) {
            evr_camera_path_free(p);
            return st;
        }
        i = j + 1;
    }
    return EVR_OK;
}

void evr_camera_path_free(evr_camera_path *p)
{
    for (int i = 0; i < p->num; i++) {
        free(p->m[i].t);
        free(p->m[i].keys);
    }
    memset(p, 0, sizeof *p);
}

/* ---- TUM files ---- */

/* The line's 8 numbers; 0 when it has another count or something else. */
static int tum_numbers(const char *line, double v[8])
{
    const char *s = line;
    int n = 0;
    for (;;) {
        char *end;
        while (*s == ' ' || *s == '\t' || *s == ',') s++;
        if (!*s || *s == '\r' || *s == '\n') break;
        if (n == 8) return 0;
        errno = 0;
        v[n] = strtod(s, &end);
        if (end == s || errno || !isfinite(v[n])) return 0;
        if (*end && *end != ' ' && *end != '\t' && *end != ',' && *end != '\r' && *end != '\n')
            return 0;
        n++;
        s = end;
    }
    return n == 8;
}

static evr_status read_tum(const char *path, evr_path_motion *m, evr_error *err)
{
    FILE *f = fopen(path, "r");
    char line[1024];
    int cap = 0, lineno = 0;
    double first = 0.0;
    evr_status st = EVR_OK;
    if (!f) FAIL("cannot open camera path file '%s': %s", path, strerror(errno));
    while (st == EVR_OK && fgets(line, sizeof line, f)) {
        double v[8];
        const char *s = line;
        lineno++;
        if (!strchr(line, '\n') && !feof(f)) {
            snprintf(err->msg, sizeof err->msg, "%s line %d: longer than %d characters", path,
                     lineno, (int)sizeof line - 2);
            st = EVR_ERR_FORMAT;
            break;
        }
        while (*s == ' ' || *s == '\t') s++;
        if (!*s || *s == '#' || *s == '\n' || *s == '\r') continue;
        if (!tum_numbers(s, v)) {
            line[strcspn(line, "\r\n")] = 0;
            snprintf(err->msg, sizeof err->msg,
                     "%s line %d: expected 8 numbers 't tx ty tz qx qy qz qw', got '%.60s'", path,
                     lineno, s);
            st = EVR_ERR_FORMAT;
            break;
        }
        const double qn = sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
        if (!(qn > 1e-6)) {
            snprintf(err->msg, sizeof err->msg, "%s line %d: the quaternion is zero", path, lineno);
            st = EVR_ERR_FORMAT;
            break;
        }
        if (m->n == 0) first = v[0];
        else if (!(v[0] - first > m->t[m->n - 1])) {
            snprintf(err->msg, sizeof err->msg,
                     "%s line %d: time %.9g is not after the line before's (%.9g): times must "
                     "increase",
                     path, lineno, v[0], m->t[m->n - 1] + first);
            st = EVR_ERR_FORMAT;
            break;
        }
        if (m->n == cap) {
            int nc = cap ? 2 * cap : 256;
            double *t = realloc(m->t, sizeof *t * (size_t)nc);
            if (t) m->t = t;
            evr_motion_key *k = t ? realloc(m->keys, sizeof *k * (size_t)nc) : NULL;
            if (k) m->keys = k;
            if (!t || !k) {
                snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
                st = EVR_ERR_NOMEM;
                break;
            }
            cap = nc;
        }
        /* the optical frame (y down, z forward) turned half a turn about x: glTF's camera axes
         * (y up, z backward); q * (0, 1, 0, 0) */
        const evr_quat q = evr_quat_make((float)(v[7] / qn), (float)(v[4] / qn), (float)(v[5] / qn),
                                         (float)(v[6] / qn));
        evr_motion_key *k = &m->keys[m->n];
        k->scale[0] = k->scale[1] = k->scale[2] = 1.0f;
        k->skew[0] = k->skew[1] = k->skew[2] = 0.0f;
        k->rot = evr_quat_normalize(evr_quat_mul(q, evr_quat_make(0, 1, 0, 0)));
        if (m->n > 0 && evr_quat_dot(k->rot, m->keys[m->n - 1].rot) < 0.0f)
            k->rot = evr_quat_make(-k->rot.w, -k->rot.x, -k->rot.y, -k->rot.z);
        k->trans = evr_v3_make((float)v[1], (float)v[2], (float)v[3]);
        m->t[m->n++] = v[0] - first;
    }
    if (st == EVR_OK && ferror(f)) {
        snprintf(err->msg, sizeof err->msg, "cannot read camera path file '%s'", path);
        st = EVR_ERR_IO;
    }
    fclose(f);
    if (st == EVR_OK && m->n == 0) {
        snprintf(err->msg, sizeof err->msg,
                 "%s: no poses (one line 't tx ty tz qx qy qz qw' per pose)", path);
        st = EVR_ERR_FORMAT;
    }
    return st;
}

double evr_camera_path_end(const evr_camera_path *p)
{
    if (p->num > 0 && p->m[0].kind == EVR_MOTION_TUM && p->m[0].n > 0)
        return p->m[0].t[p->m[0].n - 1];
    return -1.0;
}

/* The trajectory's pose at time t (clamped to its span): core/motion.h's interpolation, a pose
 * held between equal lines held bit for bit. */
static evr_m34 tum_pose(const evr_path_motion *m, double t)
{
    int lo = 0, hi = m->n - 1;
    if (m->n == 1 || t <= m->t[0]) return evr_motion_key_matrix(&m->keys[0]);
    if (t >= m->t[hi]) return evr_motion_key_matrix(&m->keys[hi]);
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        if (m->t[mid] <= t) lo = mid;
        else hi = mid;
    }
    if (evr_motion_key_same(&m->keys[lo], &m->keys[hi])) return evr_motion_key_matrix(&m->keys[lo]);
    const evr_motion_key k = evr_motion_key_lerp(&m->keys[lo], &m->keys[hi],
                                                 (float)((t - m->t[lo]) / (m->t[hi] - m->t[lo])));
    return evr_motion_key_matrix(&k);
}

int evr_camera_path_bends(const evr_camera_path *p, double t0, double t1, double *out, int n,
                          int cap)
{
    if (p->num == 0 || p->m[0].kind != EVR_MOTION_TUM) return n;
    const evr_path_motion *m = &p->m[0];
    int lo = 0, hi = m->n;
    while (lo < hi) { /* the first line after t0 */
        const int mid = lo + (hi - lo) / 2;
        if (m->t[mid] <= t0) lo = mid + 1;
        else hi = mid;
    }
    for (int i = lo; i < m->n && m->t[i] < t1 && n < cap; i++) out[n++] = m->t[i];
    return n;
}

/* ---- poses: double precision 3x4 matrices ---- */

typedef struct {
    double m[3][4];
} dm34;

static dm34 dm_of(const evr_m34 *a)
{
    dm34 d;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) d.m[i][j] = a->m[i][j];
    return d;
}

static evr_m34 m_of(const dm34 *d)
{
    evr_m34 a;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) a.m[i][j] = (float)d->m[i][j];
    return a;
}

static dm34 dm_mul(const dm34 *a, const dm34 *b)
{
    dm34 r;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 4; j++) {
            double v = j == 3 ? a->m[i][3] : 0.0;
            for (int k = 0; k < 3; k++) v += a->m[i][k] * b->m[k][j];
            r.m[i][j] = v;
        }
    }
    return r;
}

/* Rotation by angle a about the unit axis k through point c. */
static dm34 dm_turn(evr_v3 k, double a, evr_v3 c)
{
    const double x = k.x, y = k.y, z = k.z, co = cos(a), si = sin(a), t = 1.0 - co;
    const double r[3][3] = {{co + x * x * t, x * y * t - z * si, x * z * t + y * si},
                            {y * x * t + z * si, co + y * y * t, y * z * t - x * si},
                            {z * x * t - y * si, z * y * t + x * si, co + z * z * t}};
    const double cc[3] = {c.x, c.y, c.z};
    dm34 d;
    for (int i = 0; i < 3; i++) {
        double v = cc[i];
        for (int j = 0; j < 3; j++) {
            d.m[i][j] = r[i][j];
            v -= r[i][j] * cc[j];
        }
        d.m[i][3] = v;
    }
    return d;
}

static dm34 dm_move(double x, double y, double z)
{
    dm34 d;
    memset(&d, 0, sizeof d);
    d.m[0][0] = d.m[1][1] = d.m[2][2] = 1.0;
    d.m[0][3] = x;
    d.m[1][3] = y;
    d.m[2][3] = z;
    return d;
}

/* A small turn given as a rotation vector (radians) and a move, in the camera's frame. */
static dm34 dm_shake(const double w[6])
{
    const double a = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    dm34 d = a > 0.0 ? dm_turn(evr_v3_make((float)(w[0] / a), (float)(w[1] / a), (float)(w[2] / a)),
                               a, evr_v3_make(0, 0, 0))
                     : dm_move(0, 0, 0);
    d.m[0][3] = w[3];
    d.m[1][3] = w[4];
    d.m[2][3] = w[5];
    return d;
}

static double wave_sum(const evr_wave *w, double tau)
{
    double v = 0.0;
    for (int k = 0; k < EVR_SHAKE_WAVES; k++)
        v += w[k].amp * (sin(2.0 * EVR_PI_D * w[k].freq * tau + w[k].phase) - sin(w[k].phase));
    return v;
}

static dm34 apply_one(const evr_path_motion *m, double t, double tau, const dm34 *p)
{
    dm34 r;
    switch (m->kind) {
    case EVR_MOTION_ORBIT:
        r = dm_turn(m->a, 2.0 * EVR_PI_D * tau / m->period, m->c);
        return dm_mul(&r, p);
    case EVR_MOTION_DOLLY:
        r = dm_move(m->d.x * m->speed * tau, m->d.y * m->speed * tau, m->d.z * m->speed * tau);
        return dm_mul(&r, p);
    case EVR_MOTION_PAN:
    case EVR_MOTION_TILT: {
        const double deg = (m->given & (P_AMP | P_PERIOD))
                               ? m->amp * sin(2.0 * EVR_PI_D * tau / m->period)
                               : m->rate * tau;
        const double a = deg * EVR_PI_D / 180.0;
        r = m->kind == EVR_MOTION_PAN ? dm_turn(evr_v3_make(0, 1, 0), -a, evr_v3_make(0, 0, 0))
                                      : dm_turn(evr_v3_make(1, 0, 0), a, evr_v3_make(0, 0, 0));
        return dm_mul(p, &r);
    }
    case EVR_MOTION_SHAKE: {
        double w[6];
        for (int c = 0; c < 6; c++) w[c] = wave_sum(m->wave[c], tau);
        r = dm_shake(w);
        return dm_mul(p, &r);
    }
    case EVR_MOTION_TUM: {
        const evr_m34 q = tum_pose(m, t);
        return dm_of(&q);
    }
    }
    return *p;
}

evr_m34 evr_camera_path_apply(const evr_camera_path *p, double t, evr_m34 base)
{
    if (p->num == 0) return base;
    dm34 d = dm_of(&base);
    for (int i = 0; i < p->num; i++) d = apply_one(&p->m[i], t, t - p->start, &d);
    return m_of(&d);
}

/* ---- defaults ---- */

/* Waves of one shake axis: drift, 12 sinusoids between 0.2 and 2 Hz (one per equal step of
 * log frequency, at a random place in it) with amplitudes falling as 1/f, RMS drift; tremor, 8
 * between 8 and 12 Hz with Gaussian weights about 10 Hz (sd 1 Hz), RMS tremor; random phases. */
static void shake_waves(evr_wave *w, uint64_t seed, int axis, double drift, double tremor)
{
    double s2 = 0.0;
    int k;
    for (k = 0; k < 12; k++) {
        const uint64_t h = evr_hash4(seed, (uint64_t)axis, (uint64_t)k, 0x7368616b65ull);
        const double f = 0.2 * pow(10.0, (k + evr_uniform(h)) / 12.0);
        w[k].freq = f;
        w[k].amp = 1.0 / f;
        w[k].phase = 2.0 * EVR_PI_D * evr_uniform(evr_mix64(h));
        s2 += 0.5 * w[k].amp * w[k].amp;
    }
    for (k = 0; k < 12; k++) w[k].amp *= s2 > 0.0 ? drift / sqrt(s2) : 0.0;
    s2 = 0.0;
    for (k = 12; k < EVR_SHAKE_WAVES; k++) {
        const uint64_t h = evr_hash4(seed, (uint64_t)axis, (uint64_t)k, 0x7368616b65ull);
        const double f = 8.0 + 4.0 * (k - 12 + evr_uniform(h)) / (EVR_SHAKE_WAVES - 12);
        w[k].freq = f;
        w[k].amp = exp(-0.5 * (f - 10.0) * (f - 10.0));
        w[k].phase = 2.0 * EVR_PI_D * evr_uniform(evr_mix64(h));
        s2 += 0.5 * w[k].amp * w[k].amp;
    }
    for (k = 12; k < EVR_SHAKE_WAVES; k++) w[k].amp *= s2 > 0.0 ? tremor / sqrt(s2) : 0.0;
}

static evr_v3 unit3(const double v[3])
{
    const double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return evr_v3_make((float)(v[0] / l), (float)(v[1] / l), (float)(v[2] / l));
}

evr_status evr_camera_path_bind(evr_camera_path *p, const evr_path_context *ctx, evr_m34 base,
                                evr_error *err)
{
    p->start = ctx->start;
    for (int i = 0; i < p->num; i++) {
        evr_path_motion *m = &p->m[i];
        switch (m->kind) {
        case EVR_MOTION_ORBIT:
            m->c = (m->given & P_CENTRE)
                       ? evr_v3_make((float)m->centre[0], (float)m->centre[1], (float)m->centre[2])
                       : ctx->centre;
            m->a = unit3(m->axis);
            break;
        case EVR_MOTION_DOLLY: {
            if (!(m->given & P_SPEED)) m->speed = 0.1 * ctx->distance;
            if (m->given & P_DIR) {
                m->d = unit3(m->dir);
            } else { /* where the camera looks at the start, the motions before included */
                evr_camera_path before = *p;
                before.num = i;
                const evr_m34 at = evr_camera_path_apply(&before, ctx->start, base);
                m->d = evr_v3_norm(evr_v3_make(-at.m[0][2], -at.m[1][2], -at.m[2][2]));
            }
            break;
        }
        case EVR_MOTION_SHAKE: {
            const uint64_t seed = (m->given & P_SEED) ? m->seed : ctx->seed;
            const double rad = EVR_PI_D / 180.0;
            const double move = (m->given & P_MOVE) ? m->move : 0.002 * ctx->distance;
            for (int c = 0; c < 6; c++) {
                /* roll turns half as far as pitch and yaw; moves tremble a tenth of their drift */
                const double k = c == 2 ? 0.5 : 1.0;
                if (c < 3) shake_waves(m->wave[c], seed, c, k * m->amp * rad, k * m->tremor * rad);
                else shake_waves(m->wave[c], seed, c, move, 0.1 * move);
            }
            break;
        }
        case EVR_MOTION_TUM:
            if (ctx->start < 0.0 || ctx->end > m->t[m->n - 1] + 1e-9)
                FAIL("the camera path's trajectory covers 0 to %.9g s of scene time; the run goes "
                     "from %.9g to %.9g s (--start, --duration)",
                     m->t[m->n - 1], ctx->start, ctx->end);
            break;
        default: break;
        }
    }
    return EVR_OK;
}
