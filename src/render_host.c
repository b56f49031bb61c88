#include "backend.h"
#include "par_pool.h"
#include "core/hit_filter.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A part of the BSDF table's rows (70 ms on one core of machine A, every run's set-up). */
static void bsdf_rows_part(void *ctx, int k, int thread)
{
    size_t j0, j1;
    (void)thread;
    evr_par_share(EVR_BSDF_ROUGH, 4, k, &j0, &j1);
    evr_bsdf_table_fill_rows(ctx, 1024, (int)j0, (int)j1);
}

int evr_render_mesh_filter(const evr_scene *s, const evr_mesh *m)
{
    if (m->material < 0 || m->material >= s->num_materials) return 0;
    return evr_material_filter(&s->materials[m->material].p, m->uvs != NULL);
}

evr_status evr_render_host_init(evr_render_host *h, const evr_scene *s, int camera, int width,
                                int height, float ambient, evr_error *err)
{
    int i;
    memset(h, 0, sizeof *h);
    h->meshes = calloc((size_t)s->num_meshes + 1, sizeof *h->meshes);
    h->materials = calloc((size_t)s->num_materials + 1, sizeof *h->materials);
    h->textures = calloc((size_t)s->num_textures + 1, sizeof *h->textures);
    h->instances = calloc((size_t)s->num_instances + 1, sizeof *h->instances);
    h->lights = calloc((size_t)s->num_lights + 1, sizeof *h->lights);
    h->bsdf_table = malloc(2 * EVR_BSDF_MU * EVR_BSDF_ROUGH * sizeof *h->bsdf_table);
    if (!h->meshes || !h->materials || !h->textures || !h->instances || !h->lights ||
        !h->bsdf_table) {
        evr_render_host_free(h);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (i = 0; i < s->num_meshes; i++) {
        const evr_mesh *m = &s->meshes[i];
        h->meshes[i].positions = m->positions;
        h->meshes[i].normals = m->normals;
        h->meshes[i].uvs = m->uvs;
        h->meshes[i].tangents = m->tangents;
        h->meshes[i].indices = m->indices;
        h->meshes[i].num_triangles = m->num_triangles;
        h->meshes[i].material = m->material;
        h->meshes[i].filter = evr_render_mesh_filter(s, m);
    }
    for (i = 0; i < s->num_materials; i++) {
        const evr_material_params *p = &s->materials[i].p;
        h->materials[i] = *p;
        if (p->transmission > 0.0f || p->alpha_mode == EVR_ALPHA_BLEND) h->rs.translucent = 1;
    }
    {
        evr_par_pool *pool = evr_par_pool_new(evr_par_threads(4)); /* NULL: all here */
        evr_par_pool_run(pool, 4, bsdf_rows_part, h->bsdf_table);
        evr_par_pool_free(pool);
    }
    for (i = 0; i < s->num_textures; i++) {
        h->textures[i].width = s->textures[i].width;
        h->textures[i].height = s->textures[i].height;
        h->textures[i].levels = s->textures[i].levels > 0 ? s->textures[i].levels : 1;
        h->textures[i].rgba = s->textures[i].rgba;
    }
    h->deform_instance = calloc((size_t)s->num_instances + 1, sizeof *h->deform_instance);
    if (!h->deform_instance) {
        evr_render_host_free(h);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        h->instances[i].mesh = s->instances[i].mesh;
        /* Track i is node i; track num_nodes is the fixed world frame (identity). A skinned
         * mesh's vertices are in world space: its node does not move it. */
        h->instances[i].track = m->skin ? s->num_nodes : s->instances[i].node;
        h->instances[i].deform = -1;
        if (evr_instance_deforms(s, i)) {
            h->instances[i].deform = h->num_deforms;
            h->deform_instance[h->num_deforms++] = i;
        }
    }
    for (i = 0; i < s->num_lights; i++) {
        const evr_light *l = &s->lights[i];
        h->lights[i].type = (int)l->type;
        h->lights[i].track = l->node;
        memcpy(h->lights[i].color, l->color, sizeof l->color);
        h->lights[i].pos = l->position;
        h->lights[i].dir = evr_v3_norm(l->direction);
        h->lights[i].cos_inner = cosf(l->inner_cone);
        h->lights[i].cos_outer = cosf(l->outer_cone);
        h->lights[i].radius = l->type == EVR_LIGHT_DIRECTIONAL ? 0.0f : l->radius;
    }
    evr_v3 ext = evr_v3_sub(s->bounds_max, s->bounds_min);
    h->scene_size = evr_v3_len(ext);
    if (!(h->scene_size > 0.0f) || !isfinite(h->scene_size)) h->scene_size = 1.0f;

    const evr_camera_desc *cam = &s->cameras[camera];
    evr_render_scene *rs = &h->rs;
    rs->meshes = h->meshes;
    rs->materials = h->materials;
    rs->textures = h->textures;
    rs->instances = h->instances;
    rs->lights = h->lights;
    rs->num_instances = s->num_instances;
    rs->num_lights = s->num_lights;
    rs->num_deforms = h->num_deforms;
    rs->camera_track = cam->node >= 0 ? cam->node : s->num_nodes;
    rs->camera_local = cam->local;
    rs->camera = cam->ortho
                     ? evr_camera_intr_ortho(width, height, cam->ymag)
                     : evr_camera_intr_make(width, height,
                                            evr_camera_yfov(cam, (float)width / (float)height));
    rs->ambient = ambient;
    rs->ray_eps = 1e-5f * h->scene_size;
    rs->bsdf_table = h->bsdf_table;
    rs->max_bounces = 4;
    return EVR_OK;
}

void evr_render_host_free(evr_render_host *h)
{
    free(h->meshes);
    free(h->materials);
    free(h->textures);
    free(h->instances);
    free(h->lights);
    free(h->deform_instance);
    free(h->bsdf_table);
    memset(h, 0, sizeof *h);
}
