/* Ground truth in the run folder (run/labels_out.h). The dense labels come from the backends'
 * primary hits; everything about motion is evaluated here from the scene's analytic animation
 * (evr_node_world_at, evr_instance_deformed_at), not from the segments' fitted keys, so that a
 * velocity is the curves' own derivative. */
#include "run/labels_out.h"
#include "core/labels.h"
#include "io/file_commit.h"
#include "io/labels_h5.h"
#include "run/eye_labels.h"
#include "run/instance_table.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_LABEL_FRAMES 1000000
#define LABEL_POSES (EVR_LABEL_STENCIL + 2) /* t, the stencil, t + flow_dt */
#define VEL_STEP 5e-4 /* seconds: the labels' and the IMU's velocity stencil step */
#define ACC_STEP \
    5e-3                /* seconds: the IMU's acceleration step (a second difference of float
                           poses: 1e-7 m over 25e-6 s^2 is 4e-3 m/s^2) */
#define GRAVITY 9.80665 /* m/s^2, along -Y (glTF's up is +Y) */

/* What one label frame needs of an instance: its track's transform at each pose time, and for
 * a deforming instance its vertices then (and normals at t). */
typedef struct {
    int stamp; /* the frame it was evaluated for + 1; 0: never */
    evr_m34 xf[LABEL_POSES];
    float *pos[LABEL_POSES], *nrm;
} inst_cache;

struct evr_labels_out {
    /* dense labels */
    int num_times;
    double *times;
    int *seg_first;
    evr_labels_h5 *h5;
    evr_instance_table names;
    inst_cache *cache;
    float *depth, *flow, *disp, *normal;
    uint32_t *ids;
    int frames_done;
    /* 1 kHz files */
    FILE *imu, *poses;
    char *imu_path, *imu_tmp, *poses_path, *poses_tmp;
    int *animated; /* nodes written to node_poses.txt */
    int num_animated;
    long long next_sample; /* index of the next 1 kHz sample */
    evr_eye_labels *eye;
};

static evr_status nomem(evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "out of memory for ground truth");
    return EVR_ERR_NOMEM;
}

/* The camera's pose (camera to world, glTF axes) at scene time t. */
static evr_m34 camera_pose(const evr_sim *sim, double t)
{
    return evr_camera_rig_pose(&sim->rig, t); /* the camera as rendered: overrides and path */
}

evr_status evr_labels_plan(evr_sim *sim, evr_error *err)
{
    const evr_config *c = &sim->cfg;
    int i, k;
    if (c->labels_fps <= 0.0 && !c->trajectories && !c->eye_labels) return EVR_OK;
    struct evr_labels_out *L = calloc(1, sizeof *L);
    if (!L) return nomem(err);
    sim->labels = L;
    if (c->eye_labels) {
        evr_status st = evr_eye_labels_new(sim->scene, &L->eye, err);
        if (st != EVR_OK) return st;
    }
    if (c->labels_fps <= 0.0) return EVR_OK;
    double n = floor(sim->duration * c->labels_fps + 1e-9) + 1.0; /* both ends included */
    if (n > MAX_LABEL_FRAMES) {
        snprintf(err->msg, sizeof err->msg, "%.0f label frames is more than %d", n,
                 MAX_LABEL_FRAMES);
        return EVR_ERR_ARG;
    }
    L->num_times = (int)n;
    L->times = malloc(sizeof(double) * (size_t)L->num_times);
    L->seg_first = malloc(sizeof(int) * ((size_t)sim->num_segments + 1));
    if (!L->times || !L->seg_first) return nomem(err);
    for (k = 0; k < L->num_times; k++) L->times[k] = c->start + (double)k / c->labels_fps;
    /* segment i covers [start + i/fps, start + (i+1)/fps), the last one up to its end */
    for (i = 0, k = 0; i < sim->num_segments; i++) {
        int last = i + 1 == sim->num_segments;
        double t1 = c->start + (double)(i + 1) / sim->fps;
        L->seg_first[i] = k;
        while (k < L->num_times && (last || L->times[k] < t1)) k++;
    }
    L->seg_first[sim->num_segments] = k;
    return EVR_OK;
}

void evr_labels_of_segment(const evr_sim *sim, int i, int *first, int *count)
{
    const struct evr_labels_out *L = sim->labels;
    if (!L || !L->num_times) {
        *first = *count = 0;
        return;
    }
    *first = L->seg_first[i];
    *count = L->seg_first[i + 1] - L->seg_first[i];
}

const double *evr_labels_times(const evr_sim *sim)
{
    return sim->labels ? sim->labels->times : NULL;
}

static evr_status open_text(const evr_sim *sim, const char *name, char **path, char **tmp, FILE **f,
                            evr_error *err)
{
    size_t n = strlen(sim->out_dir) + strlen(name) + 2;
    *path = malloc(n);
    if (!*path) return nomem(err);
    snprintf(*path, n, "%s/%s", sim->out_dir, name);
    if (!(*tmp = evr_file_tmp_name(*path))) return nomem(err);
    *f = evr_file_create(*tmp, name, err);
    return *f ? EVR_OK : EVR_ERR_IO;
}

static evr_status open_dense(evr_sim *sim, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    const evr_scene *s = sim->scene;
    const size_t npix = (size_t)sim->cfg.width * (size_t)sim->cfg.height;
    L->cache = calloc((size_t)s->num_instances + 1, sizeof *L->cache);
    L->depth = malloc(npix * sizeof(float));
    L->ids = malloc(npix * sizeof(uint32_t));
    L->flow = malloc(2 * npix * sizeof(float));
    L->disp = malloc(2 * npix * sizeof(float));
    L->normal = malloc(3 * npix * sizeof(float));
    if (!L->cache || !L->depth || !L->ids || !L->flow || !L->disp || !L->normal ||
        !evr_instance_table_make(s, &L->names))
        return nomem(err);
    char path[4200];
    snprintf(path, sizeof path, "%s/labels.h5", sim->out_dir);
    evr_labels_h5_meta m;
    m.width = sim->cfg.width;
    m.height = sim->cfg.height;
    m.normals = sim->cfg.label_normals;
    m.fps = sim->cfg.labels_fps;
    m.flow_dt = sim->cfg.flow_dt;
    m.config_json = sim->config_json;
    m.inst_node = (const char *const *)L->names.node;
    m.inst_mesh = L->names.mesh;
    m.num_instances = L->names.n;
    return evr_labels_h5_open(path, &m, &L->h5, err);
}

evr_status evr_labels_open(evr_sim *sim, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    const evr_scene *s = sim->scene;
    evr_status st;
    int i;
    if (!L) return EVR_OK;
    if (L->num_times && (st = open_dense(sim, err)) != EVR_OK) return st;
    if (sim->cfg.trajectories) {
        if ((st = open_text(sim, "imu.txt", &L->imu_path, &L->imu_tmp, &L->imu, err)) != EVR_OK ||
            (st = open_text(sim, "node_poses.txt", &L->poses_path, &L->poses_tmp, &L->poses,
                            err)) != EVR_OK)
            return st;
        fprintf(L->imu,
                "# ideal IMU on the camera, optical frame (x right, y down, z forward)\n"
                "# gyro: angular velocity, rad/s; acc: specific force (acceleration minus "
                "gravity, %.5f m/s^2 along the world's -Y), m/s^2\n"
                "# t gx gy gz ax ay az\n",
                GRAVITY);
        L->animated = malloc(sizeof(int) * (size_t)(s->num_nodes ? s->num_nodes : 1));
        if (!L->animated) return nomem(err);
        fprintf(L->poses, "# every animated node's world pose (TUM: position, then the rotation "
                          "from the node's frame to the world as a unit quaternion)\n");
        for (i = 0; i < s->num_nodes; i++) {
            if (!evr_node_chain_animated(s, i)) continue;
            char *p = evr_node_path(s, i);
            if (!p) return nomem(err);
            fprintf(L->poses, "# node %d %s\n", i, p);
            free(p);
            L->animated[L->num_animated++] = i;
        }
        fprintf(L->poses, "# t node tx ty tz qx qy qz qw\n");
    }
    if (L->eye && (st = evr_eye_labels_open(L->eye, sim->out_dir, err)) != EVR_OK) return st;
    return EVR_OK;
}

/* The instance's evaluation for label frame `frame` at the pose times tau. */
static int eval_instance(const evr_sim *sim, inst_cache *c, int inst, int frame, const double *tau)
{
    const evr_scene *s = sim->scene;
    const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
    const int deforms = evr_instance_deforms(s, inst);
    int j;
    if (c->stamp == frame + 1) return 1;
    for (j = 0; j < LABEL_POSES; j++) {
        /* a skinned mesh's deformed vertices are in world space, its node ignored */
        c->xf[j] = deforms && m->skin ? evr_m34_identity()
                                      : evr_node_world_at(s, s->instances[inst].node, tau[j]);
        if (!deforms) continue;
        if (!c->pos[j] && !(c->pos[j] = malloc(sizeof(float) * 3 * m->num_vertices))) return 0;
        if (j == 0 && !c->nrm && !(c->nrm = malloc(sizeof(float) * 3 * m->num_vertices))) return 0;
        if (!evr_instance_deformed_at(s, inst, tau[j], c->pos[j], j == 0 ? c->nrm : NULL)) return 0;
    }
    c->stamp = frame + 1;
    return 1;
}

static evr_status dense_frame(evr_sim *sim, int frame, const evr_hit *hits, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    const evr_scene *s = sim->scene;
    const size_t npix = (size_t)sim->cfg.width * (size_t)sim->cfg.height;
    const double t = L->times[frame], h = VEL_STEP;
    const float nan = NAN;
    double off[EVR_LABEL_STENCIL], w[EVR_LABEL_STENCIL], tau[LABEL_POSES];
    double w2c[LABEL_POSES][3][4];
    int j;
    /* the curves hold still outside the animation: a stencil must not straddle its ends */
    const double lo = s->anim_end > s->anim_start ? s->anim_start : -INFINITY,
                 hi = s->anim_end > s->anim_start ? s->anim_end : INFINITY;
    evr_label_stencil(t, h, lo, hi, off, w);
    tau[0] = t;
    for (j = 0; j < EVR_LABEL_STENCIL; j++) tau[1 + j] = t + off[j] * h;
    tau[LABEL_POSES - 1] = t + sim->cfg.flow_dt;
    for (j = 0; j < LABEL_POSES; j++) {
        evr_m34 cp = camera_pose(sim, tau[j]);
        evr_label_world_to_camera(&cp, w2c[j]);
    }
    for (size_t p = 0; p < npix; p++) {
        const evr_hit *hp = &hits[p];
        L->ids[p] = 0;
        L->depth[p] = nan;
        L->flow[2 * p] = L->flow[2 * p + 1] = L->disp[2 * p] = L->disp[2 * p + 1] = nan;
        L->normal[3 * p] = L->normal[3 * p + 1] = L->normal[3 * p + 2] = nan;
        if (hp->inst < 0 || hp->inst >= s->num_instances) continue;
        const int inst = hp->inst;
        const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
        if (hp->prim >= m->num_triangles) continue;
        inst_cache *c = &L->cache[inst];
        if (!eval_instance(sim, c, inst, frame, tau)) return nomem(err);
        const uint32_t *ix = m->indices + 3 * (size_t)hp->prim;
        evr_label_pose pose[LABEL_POSES];
        float nrm[9];
        for (j = 0; j < LABEL_POSES; j++) {
            const float *vp = c->pos[0] ? c->pos[j] : m->positions;
            pose[j].inst = c->xf[j];
            memcpy(pose[j].w2c, w2c[j], sizeof w2c[j]);
            for (int v = 0; v < 3; v++)
                memcpy(pose[j].tri + 3 * v, vp + 3 * (size_t)ix[v], 3 * sizeof(float));
        }
        const float *vn = c->nrm ? c->nrm : m->normals;
        for (int v = 0; v < 3; v++) memcpy(nrm + 3 * v, vn + 3 * (size_t)ix[v], 3 * sizeof(float));
        evr_label_px px;
        evr_label_pixel(&sim->host.rs.camera, pose, nrm, hp->u, hp->v, w, h, &px);
        L->ids[p] = (uint32_t)inst + 1;
        L->depth[p] = px.depth;
        memcpy(L->flow + 2 * p, px.flow, sizeof px.flow);
        memcpy(L->disp + 2 * p, px.disp, sizeof px.disp);
        memcpy(L->normal + 3 * p, px.normal, sizeof px.normal);
    }
    return evr_labels_h5_append(L->h5, t, L->depth, L->ids, L->flow, L->disp, L->normal, err);
}

/* Rotation part of a pose with unit columns (a scaled node's scale removed). */
static void unit_rotation(const evr_m34 *m, double r[3][3])
{
    for (int j = 0; j < 3; j++) {
        double l = sqrt((double)m->m[0][j] * m->m[0][j] + (double)m->m[1][j] * m->m[1][j] +
                        (double)m->m[2][j] * m->m[2][j]);
        for (int i = 0; i < 3; i++) r[i][j] = l > 0.0 ? m->m[i][j] / l : 0.0;
    }
}

/* The camera's optical frame (x right, y down, z forward) to the world: glTF's camera axes
 * with y and z flipped. */
static void optical_rotation(const evr_m34 *pose, double r[3][3])
{
    unit_rotation(pose, r);
    for (int i = 0; i < 3; i++) {
        r[i][1] = -r[i][1];
        r[i][2] = -r[i][2];
    }
}

/* One IMU sample at t: the body-frame angular velocity from the relative rotation over
 * [t - h, t + h], the specific force from the position's second difference. */
static void imu_sample(const evr_sim *sim, double t, double gyro[3], double acc[3])
{
    const double h = VEL_STEP, ha = ACC_STEP;
    evr_m34 pm = camera_pose(sim, t - h), pp = camera_pose(sim, t + h), p0 = camera_pose(sim, t);
    evr_m34 am = camera_pose(sim, t - ha), ap = camera_pose(sim, t + ha);
    double rm[3][3], rp[3][3], r0[3][3], d[3][3];
    int i, j, k;
    optical_rotation(&pm, rm);
    optical_rotation(&pp, rp);
    optical_rotation(&p0, r0);
    for (i = 0; i < 3; i++) /* d = rm^T rp: the body's rotation over 2h */
        for (j = 0; j < 3; j++) {
            d[i][j] = 0.0;
            for (k = 0; k < 3; k++) d[i][j] += rm[k][i] * rp[k][j];
        }
    double c = 0.5 * (d[0][0] + d[1][1] + d[2][2] - 1.0);
    c = c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c;
    const double ang = acos(c), sn = sin(ang);
    const double f = sn > 1e-12 ? ang / (2.0 * sn) : 0.5; /* log map: axis * angle */
    gyro[0] = f * (d[2][1] - d[1][2]) / (2.0 * h);
    gyro[1] = f * (d[0][2] - d[2][0]) / (2.0 * h);
    gyro[2] = f * (d[1][0] - d[0][1]) / (2.0 * h);
    double a[3];
    for (i = 0; i < 3; i++)
        a[i] = ((double)ap.m[i][3] - 2.0 * (double)p0.m[i][3] + (double)am.m[i][3]) / (ha * ha);
    a[1] += GRAVITY; /* minus gravity (0, -g, 0) */
    for (i = 0; i < 3; i++) acc[i] = r0[0][i] * a[0] + r0[1][i] * a[1] + r0[2][i] * a[2];
}

static evr_status trajectories(evr_sim *sim, double t0, double t1, int last, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    for (;; L->next_sample++) {
        const double t = sim->cfg.start + (double)L->next_sample / EVR_TRAJ_RATE;
        if (last ? t > t1 + 1e-9 : t >= t1 - 1e-9) break;
        if (t < t0 - 1e-9) continue;
        if (L->imu) {
            double g[3], a[3];
            imu_sample(sim, t, g, a);
            fprintf(L->imu, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g\n", t, g[0], g[1], g[2], a[0], a[1],
                    a[2]);
            for (int k = 0; k < L->num_animated; k++) {
                evr_m34 m = evr_node_world_at(sim->scene, L->animated[k], t);
                double r[3][3];
                float rf[3][3];
                unit_rotation(&m, r);
                for (int i = 0; i < 3; i++)
                    for (int j = 0; j < 3; j++) rf[i][j] = (float)r[i][j];
                evr_quat q = evr_quat_normalize(evr_quat_from_m33(rf));
                fprintf(L->poses, "%.6f %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", t, L->animated[k],
                        m.m[0][3], m.m[1][3], m.m[2][3], q.x, q.y, q.z, q.w);
            }
        }
        if (L->eye) {
            evr_m34 cp = camera_pose(sim, t);
            evr_eye_labels_sample(L->eye, t, &cp, &sim->host.rs.camera);
        }
    }
    if ((L->imu && (ferror(L->imu) || fflush(L->imu))) ||
        (L->poses && (ferror(L->poses) || fflush(L->poses)))) {
        snprintf(err->msg, sizeof err->msg, "cannot write the trajectories in %s", sim->out_dir);
        return EVR_ERR_IO;
    }
    return L->eye ? evr_eye_labels_flush(L->eye, err) : EVR_OK;
}

evr_status evr_labels_segment(evr_sim *sim, int i, double t0, double t1, int last,
                              const evr_hit *hits, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    evr_status st;
    int first, count, k;
    if (!L) return EVR_OK;
    evr_labels_of_segment(sim, i, &first, &count);
    if (count && !hits) {
        snprintf(err->msg, sizeof err->msg, "internal error: the backend returned no label hits");
        return EVR_ERR_BACKEND;
    }
    const size_t npix = (size_t)sim->cfg.width * (size_t)sim->cfg.height;
    for (k = 0; k < count; k++)
        if ((st = dense_frame(sim, first + k, hits + (size_t)k * npix, err)) != EVR_OK) return st;
    if (count && (st = evr_labels_h5_flush(L->h5, err)) != EVR_OK) return st;
    return trajectories(sim, t0, t1, last, err);
}

static evr_status close_text(FILE **f, char *tmp, char *path, evr_status st, const char *who,
                             evr_error *err)
{
    if (!*f) return st;
    FILE *g = *f;
    *f = NULL;
    return evr_file_commit(g, tmp, path, st, who, err);
}

evr_status evr_labels_close(evr_sim *sim, evr_error *err)
{
    struct evr_labels_out *L = sim->labels;
    evr_status st = EVR_OK;
    if (!L) return EVR_OK;
    if (L->h5) {
        st = evr_labels_h5_finish(L->h5, err);
        L->h5 = NULL;
    }
    st = close_text(&L->imu, L->imu_tmp, L->imu_path, st, "imu.txt", err);
    st = close_text(&L->poses, L->poses_tmp, L->poses_path, st, "node_poses.txt", err);
    if (L->eye) st = evr_eye_labels_close(L->eye, st, err);
    return st;
}

void evr_labels_discard(evr_sim *sim)
{
    struct evr_labels_out *L = sim->labels;
    if (!L) return;
    evr_labels_h5_abort(L->h5);
    L->h5 = NULL;
    if (L->imu) evr_file_discard(L->imu, L->imu_tmp);
    if (L->poses) evr_file_discard(L->poses, L->poses_tmp);
    L->imu = L->poses = NULL;
    if (L->eye) evr_eye_labels_discard(L->eye);
}

void evr_labels_free(evr_sim *sim)
{
    struct evr_labels_out *L = sim->labels;
    int i, j;
    if (!L) return;
    evr_labels_discard(sim);
    if (L->cache) {
        for (i = 0; i < sim->scene->num_instances; i++) {
            for (j = 0; j < LABEL_POSES; j++) free(L->cache[i].pos[j]);
            free(L->cache[i].nrm);
        }
    }
    evr_instance_table_free(&L->names);
    free(L->cache);
    free(L->times);
    free(L->seg_first);
    free(L->depth);
    free(L->flow);
    free(L->disp);
    free(L->normal);
    free(L->ids);
    free(L->imu_path);
    free(L->imu_tmp);
    free(L->poses_path);
    free(L->poses_tmp);
    free(L->animated);
    evr_eye_labels_free(L->eye);
    free(L);
    sim->labels = NULL;
}
