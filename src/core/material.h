/* Materials: everything a surface's material decides at a hit, written once for direct light
 * (core/shading.h, core/shade.h), the photon pass (core/photon.h) and the path tracer
 * (src/cpu/still.c):
 *   - the material record at the hit (evr_material_at: base colour times texture, emission),
 *   - emission (evr_material_emission),
 *   - the BSDF for a light direction (evr_material_add_light, then evr_material_radiance),
 *   - the photon pass's stay / diffuse / mirror decision (evr_material_photon_event), the path
 *     tracer's diffuse / mirror choice (evr_material_path_event) and the bounce directions,
 *   - the diffuse share that turns an irradiance estimate into radiance (evr_material_diffuse_k).
 * The model today is Lambert (albedo / pi) plus a mirror share for indirect light. A new model
 * (glTF metallic-roughness: GGX/Smith with Fresnel, transmission) adds its parameters to
 * evr_material_params and evr_material_defaults below, fills in these functions (and the record
 * in evr_surface), and reads the parameters in scene/import_mesh.c; the callers pass the shading
 * frame (evr_surface's n), wo and wi already.
 * Floating-point expressions here are the ones the golden events were made with: keep their
 * order when editing (the GPU must not gain or lose fused multiply-adds). */
#ifndef EVR_CORE_MATERIAL_H
#define EVR_CORE_MATERIAL_H

#include "core/render_scene.h"

#define EVR_PI 3.14159265358979f

/* A texture as a material uses it: which texture, the KHR_texture_transform of its uv (identity
 * when absent), and the slot's scale (normalTexture.scale, occlusionTexture.strength, else 1). */
typedef struct {
    int index;   /* into the textures, -1: none */
    float xf[6]; /* uv' = (xf[0] u + xf[1] v + xf[2], xf[3] u + xf[4] v + xf[5]) */
    float scale;
} evr_texture_ref;

/* The textures a glTF material may give. Base colour and emissive are sRGB-encoded in their
 * files and held linear; the others hold data and are never linearized (import_texture.c). */
enum {
    EVR_TEX_BASE = 0,           /* base colour (rgb) and alpha (a) */
    EVR_TEX_METALLIC_ROUGHNESS, /* roughness in g, metallic in b */
    EVR_TEX_NORMAL,             /* tangent-space normal, rgb in [0,1] -> [-1,1] */
    EVR_TEX_OCCLUSION,          /* ambient occlusion in r */
    EVR_TEX_EMISSIVE,           /* emissive colour (rgb) */
    EVR_TEX_TRANSMISSION,       /* KHR_materials_transmission: r */
    EVR_TEX_COUNT
};

enum { EVR_ALPHA_OPAQUE = 0, EVR_ALPHA_MASK = 1, EVR_ALPHA_BLEND = 2 };

/* What a material is: the scene holds one per material (scene/scene.h), the backends read them
 * (evr_render_scene.materials): glTF 2.0 metallic-roughness with the KHR_materials extensions
 * evray renders. A new parameter goes here, its default in evr_material_defaults below and its
 * reading in scene/import_mesh.c. */
struct evr_material_params {
    float base_color[4]; /* linear RGBA factor */
    float emissive[3];   /* linear RGB, radiance units: emissiveFactor times emissive_strength */
    /* the photon pass's thresholds, 0 <= t_diffuse <= t_specular <= 1: from the material's
     * extras "t_diffuse" and "t_specular" when the glTF gives them, else from the BSDF
     * (evr_photon_material_map) */
    float t_diffuse, t_specular;
    float metallic, roughness;  /* factors (perceptual roughness; GGX alpha = roughness^2) */
    int alpha_mode;             /* EVR_ALPHA_* */
    float alpha_cutoff;         /* MASK: alpha below it is a hole */
    int double_sided;           /* 0: back faces are culled for camera and secondary rays */
    int unlit;                  /* KHR_materials_unlit: radiance = base colour */
    float transmission;         /* KHR_materials_transmission factor */
    float ior;                  /* KHR_materials_ior (1.5) */
    float specular;             /* KHR_materials_specular factor (1) */
    float specular_color[3];    /* KHR_materials_specular colour factor (1, 1, 1) */
    float thickness;            /* KHR_materials_volume: 0 thin-walled */
    float attenuation_distance; /* KHR_materials_volume: INFINITY none */
    float attenuation_color[3];
    evr_texture_ref tex[EVR_TEX_COUNT];
};

/* A surface point as shading sees it: its shading frame (position, normal) and the hit's
 * material record (the material evaluated there, textures applied). */
typedef struct {
    evr_v3 p; /* world position */
    evr_v3 n; /* world shading normal, facing the incoming ray */
    float albedo[3];
    float emissive[3];
    /* the ray's footprint at the hit in uv units, as log2 of its width (evr_texture_lod; a
     * texture's level: evr_texture_level); EVR_TEX_LOD_SHARPEST: level 0 */
    float tex_lod;
} evr_surface;

/* A footprint of no width: every texture's level 0. */
#define EVR_TEX_LOD_SHARPEST (-100.0f)

/* Bilinear texture lookup with repeat wrapping; glTF uv (0,0) is the image's top-left. */
EVR_HD static inline void evr_texture_bilinear(const evr_texture_view *t, float u, float v,
                                               float out[4])
{
    float x = u * (float)t->width - 0.5f, y = v * (float)t->height - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float ax = x - fx, ay = y - fy;
    int x0 = (int)fx % t->width, y0 = (int)fy % t->height;
    if (x0 < 0) x0 += t->width;
    if (y0 < 0) y0 += t->height;
    int x1 = (x0 + 1) % t->width, y1 = (y0 + 1) % t->height;
    const float *p00 = t->rgba + 4 * ((long)y0 * t->width + x0),
                *p10 = t->rgba + 4 * ((long)y0 * t->width + x1);
    const float *p01 = t->rgba + 4 * ((long)y1 * t->width + x0),
                *p11 = t->rgba + 4 * ((long)y1 * t->width + x1);
    int c;
    for (c = 0; c < 4; c++)
        out[c] =
            (p00[c] * (1 - ax) + p10[c] * ax) * (1 - ay) + (p01[c] * (1 - ax) + p11[c] * ax) * ay;
}

/* ---- textures filtered by the ray's footprint: mip levels (core/render_scene.h's layout) ---- */

/* Trilinear lookup: bilinear (evr_texture_bilinear, repeat wrapping) in levels floor(lod) and
 * floor(lod) + 1, blended by lod's fraction; lod is clamped to [0, t->levels - 1] (lod 0 is
 * evr_texture_bilinear of level 0 exactly). */
EVR_HD static inline void evr_texture_sample(const evr_texture_view *t, float u, float v, float lod,
                                             float out[4])
{
    const float l = fminf(fmaxf(lod, 0.0f), (float)(t->levels - 1));
    const int k = (int)floorf(l);
    const float a = l - (float)k;
    evr_texture_view lv = evr_texture_level_view(t, k);
    evr_texture_bilinear(&lv, u, v, out);
    if (a > 0.0f) { /* k + 1 < levels: the next level follows this one */
        float o1[4];
        lv.rgba += 4 * (long)lv.width * lv.height;
        lv.width = evr_mip_size(t->width, k + 1);
        lv.height = evr_mip_size(t->height, k + 1);
        evr_texture_bilinear(&lv, u, v, o1);
        for (int c = 0; c < 4; c++) out[c] = out[c] * (1.0f - a) + o1[c] * a;
    }
}

/* The footprint of a ray cone at a hit in uv units, as log2 of its width: the cone's width there
 * (world units) stretched by 1 / |cos| of the angle between the ray and the triangle's normal,
 * times the triangle's uv per world length, sqrt(uv_area / world_area) (the ray-cone level of
 * detail of Akenine-Moller et al., "Texture Level of Detail Strategies for Real-Time Ray
 * Tracing", Ray Tracing Gems, ch. 20, with the texture's size left to evr_texture_level). The
 * areas may both be doubled. EVR_TEX_LOD_SHARPEST for a cone of no width or a degenerate
 * triangle. */
EVR_HD static inline float evr_texture_lod(float cone_width, float cos_theta, float world_area,
                                           float uv_area)
{
    if (!(cone_width > 0.0f) || !(world_area > 0.0f) || !(uv_area > 0.0f))
        return EVR_TEX_LOD_SHARPEST;
    const float c = fmaxf(fabsf(cos_theta), 1e-4f); /* grazing: the coarsest level anyway */
    return fmaxf(log2f(cone_width / c * sqrtf(uv_area / world_area)), EVR_TEX_LOD_SHARPEST);
}

/* The level of texture t, used by slot r, for a footprint of lod_uv (evr_texture_lod): its
 * texels per uv unit, sqrt(width * height), times the slot's uv transform's scale,
 * sqrt(|det|) of its 2 x 2 part, added in log2. */
EVR_HD static inline float evr_texture_level(const evr_texture_view *t, const evr_texture_ref *r,
                                             float lod_uv)
{
    const float det = fabsf(r->xf[0] * r->xf[4] - r->xf[1] * r->xf[3]);
    return lod_uv + 0.5f * log2f((float)t->width * (float)t->height * fmaxf(det, 1e-30f));
}

/* Whether material mat samples any texture. */
EVR_HD static inline int evr_material_textured(const evr_material_params *mat)
{
    for (int i = 0; i < EVR_TEX_COUNT; i++)
        if (mat->tex[i].index >= 0) return 1;
    return 0;
}

/* The uv a texture slot samples at mesh uv (u, v): its KHR_texture_transform applied. */
EVR_HD static inline void evr_texture_uv(const evr_texture_ref *t, float u, float v, float *tu,
                                         float *tv)
{
    *tu = t->xf[0] * u + t->xf[1] * v + t->xf[2];
    *tv = t->xf[3] * u + t->xf[4] * v + t->xf[5];
}

/* The material record of s at barycentrics (w, u, v) of the triangle (i0, i1, i2) of mesh m;
 * textures are filtered by the footprint s->tex_lod (evr_surface_at sets it first). */
EVR_HD static inline void evr_material_at(const evr_render_scene *rs, const evr_mesh_view *m,
                                          uint32_t i0, uint32_t i1, uint32_t i2, float w, float u,
                                          float v, evr_surface *s)
{
    const evr_material_params *mat = &rs->materials[m->material];
    s->albedo[0] = mat->base_color[0];
    s->albedo[1] = mat->base_color[1];
    s->albedo[2] = mat->base_color[2];
    if (mat->tex[EVR_TEX_BASE].index >= 0 && m->uvs) {
        float tu = w * m->uvs[2 * i0] + u * m->uvs[2 * i1] + v * m->uvs[2 * i2];
        float tv = w * m->uvs[2 * i0 + 1] + u * m->uvs[2 * i1 + 1] + v * m->uvs[2 * i2 + 1];
        float tex[4];
        const evr_texture_view *t = &rs->textures[mat->tex[EVR_TEX_BASE].index];
        evr_texture_sample(t, tu, tv, evr_texture_level(t, &mat->tex[EVR_TEX_BASE], s->tex_lod),
                           tex);
        s->albedo[0] *= tex[0];
        s->albedo[1] *= tex[1];
        s->albedo[2] *= tex[2];
    }
    s->emissive[0] = mat->emissive[0];
    s->emissive[1] = mat->emissive[1];
    s->emissive[2] = mat->emissive[2];
}

/* Radiance s emits towards wo (both sides emit). */
EVR_HD static inline void evr_material_emission(const evr_surface *s, evr_v3 wo, float out[3])
{
    (void)wo;
    out[0] = s->emissive[0];
    out[1] = s->emissive[1];
    out[2] = s->emissive[2];
}

/* ---- direct light: the BSDF for a light direction ---- */

/* Adds one unshadowed light's contribution at s, seen along wo, arriving along wi with
 * irradiance e_rgb (on a surface facing it), to acc. Lambert: acc sums irradiance times cosine;
 * the BSDF's albedo / pi is applied once, in evr_material_radiance. */
EVR_HD static inline void evr_material_add_light(const evr_surface *s, evr_v3 wo, evr_v3 wi,
                                                 const float e_rgb[3], float acc[3])
{
    (void)wo;
    float c = evr_v3_dot(s->n, wi);
    if (c <= 0.0f) return;
    acc[0] += e_rgb[0] * c;
    acc[1] += e_rgb[1] * c;
    acc[2] += e_rgb[2] * c;
}

/* Radiance leaving s towards wo (RGB) from the lights' sum acc (evr_material_add_light), the
 * ambient irradiance (a fraction of pi) and its emission. */
EVR_HD static inline void evr_material_radiance(const evr_surface *s, evr_v3 wo, const float acc[3],
                                                float ambient, float rgb[3])
{
    (void)wo;
    rgb[0] = s->albedo[0] * (ambient + acc[0] / EVR_PI) + s->emissive[0];
    rgb[1] = s->albedo[1] * (ambient + acc[1] / EVR_PI) + s->emissive[1];
    rgb[2] = s->albedo[2] * (ambient + acc[2] / EVR_PI) + s->emissive[2];
}

/* ---- indirect light: photon thresholds, decisions and bounce directions ---- */

/* glTF metallic-roughness to the photon thresholds: reflectance R = max(base colour) clamped to
 * [0.05, 0.95]; mirror = metallic * (1 - roughness);
 * t_diffuse = 1 - R, t_specular = t_diffuse + R * (1 - mirror). */
EVR_HD static inline void evr_photon_material_map(const float base_color[3], float metallic,
                                                  float roughness, float *t_diffuse,
                                                  float *t_specular)
{
    float r = fmaxf(base_color[0], fmaxf(base_color[1], base_color[2]));
    float m = fminf(fmaxf(metallic, 0.0f), 1.0f) * (1.0f - fminf(fmaxf(roughness, 0.0f), 1.0f));
    r = fminf(fmaxf(r, 0.05f), 0.95f);
    *t_diffuse = 1.0f - r;
    *t_specular = *t_diffuse + r * (1.0f - m);
}

/* A texture slot with nothing in it. */
static inline void evr_texture_ref_none(evr_texture_ref *t)
{
    t->index = -1;
    t->xf[0] = 1.0f, t->xf[1] = 0.0f, t->xf[2] = 0.0f;
    t->xf[3] = 0.0f, t->xf[4] = 1.0f, t->xf[5] = 0.0f;
    t->scale = 1.0f;
}

/* A material before the file says anything of it: the glTF defaults (white, untextured,
 * metallic 1 and roughness 1 in the spec; evray keeps metallic 0 for a material that gives no
 * pbrMetallicRoughness, as Assimp reports it), opaque, single-sided, IOR 1.5. */
static inline void evr_material_defaults(evr_material_params *m)
{
    m->base_color[0] = m->base_color[1] = m->base_color[2] = m->base_color[3] = 1.0f;
    m->emissive[0] = m->emissive[1] = m->emissive[2] = 0.0f;
    m->metallic = 0.0f;
    m->roughness = 1.0f;
    m->alpha_mode = EVR_ALPHA_OPAQUE;
    m->alpha_cutoff = 0.5f;
    m->double_sided = 0;
    m->unlit = 0;
    m->transmission = 0.0f;
    m->ior = 1.5f;
    m->specular = 1.0f;
    m->specular_color[0] = m->specular_color[1] = m->specular_color[2] = 1.0f;
    m->thickness = 0.0f;
    m->attenuation_distance = INFINITY;
    m->attenuation_color[0] = m->attenuation_color[1] = m->attenuation_color[2] = 1.0f;
    for (int i = 0; i < EVR_TEX_COUNT; i++) evr_texture_ref_none(&m->tex[i]);
    evr_photon_material_map(m->base_color, m->metallic, m->roughness, &m->t_diffuse,
                            &m->t_specular);
}

/* Share of the reflected light that is a mirror reflection. */
EVR_HD static inline float evr_photon_mirror_share(float t_diffuse, float t_specular)
{
    float refl = 1.0f - t_diffuse;
    return refl > 0.0f ? fminf(fmaxf((1.0f - t_specular) / refl, 0.0f), 1.0f) : 0.0f;
}

enum { EVR_PHOTON_STAY = 0, EVR_PHOTON_DIFFUSE = 1, EVR_PHOTON_MIRROR = 2, EVR_PHOTON_ABSORB = 3 };

/* The decision at a hit for random xi in [0, 1). *weight multiplies the flux: stay 1/t_diffuse,
 * bounce 1/(1 - t_diffuse) (times the albedo, which the caller applies), 1 for a bounce when
 * staying is not allowed. ABSORB only when nothing else is possible. */
EVR_HD static inline int evr_photon_scatter(float t_diffuse, float t_specular, float xi,
                                            int allow_stay, float *weight)
{
    float td = fminf(fmaxf(t_diffuse, 0.0f), 1.0f), ts = fminf(fmaxf(t_specular, td), 1.0f);
    if (allow_stay) {
        if (xi < td) {
            *weight = 1.0f / td;
            return EVR_PHOTON_STAY;
        }
        if (td >= 1.0f) {
            *weight = 0.0f;
            return EVR_PHOTON_ABSORB;
        }
        *weight = 1.0f / (1.0f - td);
        return xi < ts ? EVR_PHOTON_DIFFUSE : EVR_PHOTON_MIRROR;
    }
    if (td >= 1.0f) {
        *weight = 0.0f;
        return EVR_PHOTON_ABSORB;
    }
    *weight = 1.0f;
    /* xi spread over the bounce options only */
    return td + xi * (1.0f - td) < ts ? EVR_PHOTON_DIFFUSE : EVR_PHOTON_MIRROR;
}

/* Orthonormal basis around unit n (Duff et al. 2017). */
EVR_HD static inline void evr_onb(evr_v3 n, evr_v3 *t, evr_v3 *b)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z), c = n.x * n.y * a;
    *t = evr_v3_make(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = evr_v3_make(c, s + n.y * n.y * a, -n.y);
}

/* Cosine-distributed direction around unit n from (u1, u2) in [0, 1)^2 (pdf cos / pi). */
EVR_HD static inline evr_v3 evr_cosine_dir(evr_v3 n, float u1, float u2)
{
    evr_v3 t, b;
    float r = sqrtf(u1), phi = 6.28318530718f * u2;
    float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    evr_onb(n, &t, &b);
    return evr_v3_norm(
        evr_v3_add(evr_v3_add(evr_v3_scale(t, x), evr_v3_scale(b, y)), evr_v3_scale(n, z)));
}

/* Mirror direction of incoming d about unit n. */
EVR_HD static inline evr_v3 evr_mirror_dir(evr_v3 d, evr_v3 n)
{
    return evr_v3_sub(d, evr_v3_scale(n, 2.0f * evr_v3_dot(d, n)));
}

/* The photon pass's decision at a hit of material mat for random xi in [0, 1) (d_in: the
 * photon's direction of travel): evr_photon_scatter's event and *weight. */
EVR_HD static inline int evr_material_photon_event(const evr_material_params *mat,
                                                   const evr_surface *s, evr_v3 d_in, float xi,
                                                   int allow_stay, float *weight)
{
    (void)s;
    (void)d_in;
    return evr_photon_scatter(mat->t_diffuse, mat->t_specular, xi, allow_stay, weight);
}

/* The path tracer's choice at a hit of material mat for random xi in [0, 1): EVR_PHOTON_MIRROR
 * with the mirror share's odds, else EVR_PHOTON_DIFFUSE (it never stays). */
EVR_HD static inline int evr_material_path_event(const evr_material_params *mat,
                                                 const evr_surface *s, evr_v3 d_in, float xi)
{
    (void)s;
    (void)d_in;
    float ms = evr_photon_mirror_share(mat->t_diffuse, mat->t_specular);
    return xi < ms ? EVR_PHOTON_MIRROR : EVR_PHOTON_DIFFUSE;
}

/* The direction a bounce of kind ev (EVR_PHOTON_DIFFUSE or EVR_PHOTON_MIRROR) leaves s in, for a
 * ray travelling along d_in; (u1, u2) in [0, 1)^2 pick the diffuse direction. */
EVR_HD static inline evr_v3 evr_material_bounce_dir(const evr_surface *s, int ev, evr_v3 d_in,
                                                    float u1, float u2)
{
    return ev == EVR_PHOTON_DIFFUSE ? evr_cosine_dir(s->n, u1, u2)
                                    : evr_v3_norm(evr_mirror_dir(d_in, s->n));
}

/* What multiplies the albedo and an irradiance for the indirect (diffusely reflected) radiance
 * leaving a surface of material mat: the diffuse share over pi. */
EVR_HD static inline float evr_material_diffuse_k(const evr_material_params *mat)
{
    return (1.0f - evr_photon_mirror_share(mat->t_diffuse, mat->t_specular)) / EVR_PI;
}

#endif
