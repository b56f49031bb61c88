/* Materials: everything a surface's material decides at a hit, written once for direct light
 * (core/shading.h, core/shade.h), specular paths (core/path.h), the photon pass (core/photon.h)
 * and the path tracer (src/cpu/still.c):
 *   - the material record at the hit (evr_material_at: base colour times texture, emission, and
 *     the BSDF's view-dependent weights, evr_material_view / evr_material_lobes),
 *   - emission (evr_material_emission),
 *   - the BSDF for a light direction (evr_material_add_light, then evr_material_radiance).
 * The model is glTF 2.0's metallic-roughness (Lambert + GGX/Smith with Fresnel, the parts in
 * core/bsdf.h) with transmission. Indirect light samples the same BSDF: core/bsdf_sample.h
 * draws its lobes (diffuse, glossy or mirror, transmission) for the photon pass and the path
 * tracer, and the photon gather weighs an irradiance with evr_surface's diffuse weight
 * (core/photon_indirect.h).
 * A new parameter goes into evr_material_params and evr_material_defaults below, is read in
 * scene/import_gltf_material.c (and scene/import_material.c for other formats), and shapes the
 * record in evr_surface.
 * Floating-point expressions here are the ones the golden events were made with: keep their
 * order when editing (the GPU must not gain or lose fused multiply-adds). */
#ifndef EVR_CORE_MATERIAL_H
#define EVR_CORE_MATERIAL_H

#include "core/render_scene.h"
#include "core/bsdf.h"

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
 * reading in scene/import_gltf_material.c (scene/import_material.c for other formats). */
struct evr_material_params {
    float base_color[4]; /* linear RGBA factor */
    float emissive[3];   /* linear RGB, radiance units: emissiveFactor times emissive_strength */
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

/* A surface point as shading sees it: its shading frame and the hit's material record (the
 * material evaluated there, textures applied, the BSDF's view-dependent weights for the
 * direction it is seen from). */
typedef struct {
    evr_v3 p;             /* world position */
    evr_v3 n;             /* world shading normal (normal map applied), facing the incoming ray */
    evr_v3 nv;            /* the interpolated vertex normal, facing the incoming ray */
    float albedo[3];      /* base colour: factor times texture */
    float emissive[3];    /* emitted radiance */
    float diffuse[3];     /* the diffuse base's reflectance: what the specular layer leaves */
    float f0[3], f90;     /* the specular lobe's Fresnel at normal and grazing incidence */
    float comp[3];        /* the lobe's multiple-scattering compensation (1: none) */
    float spec_albedo[3]; /* the specular lobe's directional albedo seen from the viewer */
    float transmit[3];    /* the share transmitted through the surface (transmission) */
    float transmission;   /* the transmission factor (times its texture) */
    float metallic;
    float rough, alpha;      /* perceptual roughness and GGX alpha */
    float opacity;           /* BLEND: coverage (base alpha); 1 otherwise */
    float occlusion;         /* ambient occlusion (1: none) */
    float eta;               /* ratio of IORs outside / inside for a ray entering (1 / ior) */
    const float *bsdf_table; /* core/bsdf.h's table (NULL: single scattering only) */
    int material;
    int unlit;
    int front; /* the ray met the face the vertex normals point out of */
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

/* Texture slot t at mesh uv (u, v), filtered for the footprint lod (evr_surface.tex_lod); 0
 * when the slot is empty (out untouched). */
EVR_HD static inline int evr_material_texture(const evr_render_scene *rs, const evr_texture_ref *t,
                                              float u, float v, float lod, float out[4])
{
    if (t->index < 0) return 0;
    float tu, tv;
    const evr_texture_view *tex = &rs->textures[t->index];
    evr_texture_uv(t, u, v, &tu, &tv);
    evr_texture_sample(tex, tu, tv, evr_texture_level(tex, t, lod), out);
    return 1;
}

/* Opacity of material mat at mesh uv (u, v) (uv_ok 0: the mesh has none): base alpha. */
EVR_HD static inline float evr_material_alpha(const evr_render_scene *rs,
                                              const evr_material_params *mat, int uv_ok, float u,
                                              float v)
{
    float a = mat->base_color[3], tex[4];
    if (uv_ok && evr_material_texture(rs, &mat->tex[EVR_TEX_BASE], u, v, EVR_TEX_LOD_SHARPEST, tex))
        a *= tex[3];
    return a;
}

/* The view-dependent weights of a surface seen at cos mu (> 0) from the side of its normal:
 * the specular lobe's albedo from the table (core/bsdf.h; NULL: single scattering only), its
 * multiple-scattering compensation, the diffuse base scaled by what the dielectric layer leaves,
 * and the transmitted share; f0 and f90 of the lobe with them. The surface is material mat's
 * with base colour albedo, metallic m, perceptual roughness rough and transmission tr (the
 * factor times its texture). evr_material_view fills evr_surface with them for the direction it
 * is seen from; the photon pass asks them for the direction a photon leaves in
 * (core/bsdf_sample.h), so light and camera paths weigh a bounce alike. */
EVR_HD static inline void evr_material_lobes(const float *table, const evr_material_params *mat,
                                             const float albedo[3], float m, float rough, float tr,
                                             float mu, float f0[3], float *f90, float comp[3],
                                             float diffuse[3], float transmit[3],
                                             float spec_albedo[3])
{
    float ta = 1.0f, tb = 0.0f;
    if (table) evr_bsdf_table_ab(table, mu, rough, &ta, &tb);
    const float e1 = fmaxf(ta + tb, 1e-3f);
    /* the dielectric layer: f0 from the IOR and KHR_materials_specular, f90 its factor */
    const float r = (mat->ior - 1.0f) / (mat->ior + 1.0f);
    for (int c = 0; c < 3; c++) {
        const float f0d = fminf(r * r * mat->specular_color[c], 1.0f) * mat->specular;
        const float f90d = mat->specular;
        const float compd = 1.0f + f0d * (1.0f / e1 - 1.0f);
        const float ed = fminf((f0d * ta + f90d * tb) * compd, 1.0f);
        f0[c] = f0d + (albedo[c] - f0d) * m;
        comp[c] = 1.0f + f0[c] * (1.0f / e1 - 1.0f);
        diffuse[c] = (1.0f - m) * (1.0f - tr) * albedo[c] * (1.0f - ed);
        transmit[c] = (1.0f - m) * tr * albedo[c] * (1.0f - ed);
    }
    *f90 = mat->specular + (1.0f - mat->specular) * m;
    for (int c = 0; c < 3; c++) spec_albedo[c] = fminf((f0[c] * ta + *f90 * tb) * comp[c], 1.0f);
}

/* The view-dependent weights of s seen along wo (unit, on the side of s->n): evr_material_lobes
 * at cos(n, wo), the material mat's with transmission factor `transmission` (its factor times
 * its texture). Called once the frame and the parameters are set. */
EVR_HD static inline void evr_material_view(const evr_render_scene *rs,
                                            const evr_material_params *mat, float transmission,
                                            evr_v3 wo, evr_surface *s)
{
    const float mu = fmaxf(evr_v3_dot(s->n, wo), 1e-4f);
    s->bsdf_table = rs->bsdf_table;
    s->transmission = transmission;
    evr_material_lobes(rs->bsdf_table, mat, s->albedo, s->metallic, s->rough, transmission, mu,
                       s->f0, &s->f90, s->comp, s->diffuse, s->transmit, s->spec_albedo);
}

/* Perceptual roughness below which a surface reflects (and refracts) along one ray: a mirror
 * or near-mirror, whose reflected scene the ambient term cannot stand for. */
#define EVR_MIRROR_ROUGHNESS 0.2f

/* The material record of s at barycentrics (w, u, v) of the triangle (i0, i1, i2) of mesh m,
 * seen along wo. The caller has set s->p, s->nv (the vertex normal facing the ray, unit) and
 * s->front; tw is the interpolated tangent in world space (xyz, not unit) and tsign its
 * bitangent sign, used when the material has a normal texture and the mesh tangents. */
EVR_HD static inline void evr_material_at(const evr_render_scene *rs, const evr_mesh_view *m,
                                          uint32_t i0, uint32_t i1, uint32_t i2, float w, float u,
                                          float v, evr_v3 tw, float tsign, evr_v3 wo,
                                          evr_surface *s)
{
    const evr_material_params *mat = &rs->materials[m->material];
    const int uv_ok = m->uvs != 0;
    float tu = 0.0f, tv = 0.0f, tex[4];
    if (uv_ok) {
        tu = w * m->uvs[2 * i0] + u * m->uvs[2 * i1] + v * m->uvs[2 * i2];
        tv = w * m->uvs[2 * i0 + 1] + u * m->uvs[2 * i1 + 1] + v * m->uvs[2 * i2 + 1];
    }
    s->material = m->material;
    s->unlit = mat->unlit;
    s->albedo[0] = mat->base_color[0];
    s->albedo[1] = mat->base_color[1];
    s->albedo[2] = mat->base_color[2];
    s->opacity = mat->alpha_mode == EVR_ALPHA_BLEND ? mat->base_color[3] : 1.0f;
    if (uv_ok && evr_material_texture(rs, &mat->tex[EVR_TEX_BASE], tu, tv, s->tex_lod, tex)) {
        s->albedo[0] *= tex[0];
        s->albedo[1] *= tex[1];
        s->albedo[2] *= tex[2];
        if (mat->alpha_mode == EVR_ALPHA_BLEND) s->opacity *= tex[3];
    }
    s->emissive[0] = mat->emissive[0];
    s->emissive[1] = mat->emissive[1];
    s->emissive[2] = mat->emissive[2];
    if (uv_ok && evr_material_texture(rs, &mat->tex[EVR_TEX_EMISSIVE], tu, tv, s->tex_lod, tex)) {
        s->emissive[0] *= tex[0];
        s->emissive[1] *= tex[1];
        s->emissive[2] *= tex[2];
    }
    s->metallic = fminf(fmaxf(mat->metallic, 0.0f), 1.0f);
    s->rough = fminf(fmaxf(mat->roughness, 0.0f), 1.0f);
    if (uv_ok &&
        evr_material_texture(rs, &mat->tex[EVR_TEX_METALLIC_ROUGHNESS], tu, tv, s->tex_lod, tex)) {
        s->rough *= tex[1];
        s->metallic *= tex[2];
    }
    s->alpha = fmaxf(s->rough * s->rough, EVR_GGX_ALPHA_MIN);
    s->occlusion = 1.0f;
    if (uv_ok && evr_material_texture(rs, &mat->tex[EVR_TEX_OCCLUSION], tu, tv, s->tex_lod, tex))
        s->occlusion = 1.0f + mat->tex[EVR_TEX_OCCLUSION].scale * (tex[0] - 1.0f);
    s->eta = 1.0f / fmaxf(mat->ior, 1.0f);
    s->n = s->nv;
    /* normal map: the tangent frame Gram-Schmidt orthogonalized against the vertex normal as the
     * ray sees it (a back face's normal is flipped, its bitangent with it) */
    if (uv_ok && m->tangents &&
        evr_material_texture(rs, &mat->tex[EVR_TEX_NORMAL], tu, tv, s->tex_lod, tex)) {
        const float ns = mat->tex[EVR_TEX_NORMAL].scale;
        evr_v3 t = evr_v3_sub(tw, evr_v3_scale(s->nv, evr_v3_dot(tw, s->nv)));
        const float tl = evr_v3_len(t);
        if (tl > 1e-12f) {
            t = evr_v3_scale(t, 1.0f / tl);
            const float side = s->front ? 1.0f : -1.0f;
            const evr_v3 b = evr_v3_scale(evr_v3_cross(s->nv, t), tsign * side);
            const float x = (2.0f * tex[0] - 1.0f) * ns, y = (2.0f * tex[1] - 1.0f) * ns,
                        z = 2.0f * tex[2] - 1.0f;
            evr_v3 n = evr_v3_add(evr_v3_add(evr_v3_scale(t, x), evr_v3_scale(b, y)),
                                  evr_v3_scale(s->nv, z));
            const float nl = evr_v3_len(n);
            if (nl > 1e-12f) {
                n = evr_v3_scale(n, 1.0f / nl);
                /* a mapped normal facing away from the viewer is bent back to the horizon */
                const float c = evr_v3_dot(n, wo);
                if (c < 1e-3f) n = evr_v3_norm(evr_v3_add(n, evr_v3_scale(wo, 1e-3f - c)));
                s->n = n;
            }
        }
    }
    float tr = mat->transmission;
    if (uv_ok && evr_material_texture(rs, &mat->tex[EVR_TEX_TRANSMISSION], tu, tv, s->tex_lod, tex))
        tr *= tex[0];
    evr_material_view(rs, mat, tr, wo, s);
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

/* The GGX alpha with which s reflects a light whose sphere subtends the half-angle `spread`
 * (radius over distance): a mirror's reflection of the sphere spans that angle, its half
 * vectors half of it, so the lobe widens by spread / 2. */
EVR_HD static inline float evr_material_light_alpha(const evr_surface *s, float spread)
{
    return fminf(s->alpha + 0.5f * spread, 1.0f);
}

/* Adds one unshadowed light's contribution at s, seen along wo, arriving along wi with
 * irradiance e_rgb (on a surface facing it) from a sphere of angular radius spread, to acc:
 * the BSDF times the cosine times the irradiance (radiance, RGB). */
EVR_HD static inline void evr_material_add_light(const evr_surface *s, evr_v3 wo, evr_v3 wi,
                                                 const float e_rgb[3], float spread, float acc[3])
{
    if (s->unlit) return;
    const float nl = evr_v3_dot(s->n, wi);
    if (nl <= 0.0f) return;
    const float nv = fmaxf(evr_v3_dot(s->n, wo), 1e-4f);
    const evr_v3 h = evr_v3_norm(evr_v3_add(wi, wo));
    const float nh = fmaxf(evr_v3_dot(s->n, h), 0.0f), vh = fmaxf(evr_v3_dot(wo, h), 0.0f);
    const float a = evr_material_light_alpha(s, spread);
    const float dv = evr_ggx_d(a, nh) * evr_smith_v(a, nl, nv), fw = evr_schlick_w(vh);
    float e1w = 0.0f; /* the widened lobe's own compensation keeps its energy */
    if (a > s->alpha && s->bsdf_table) {
        float ta, tb;
        evr_bsdf_table_ab(s->bsdf_table, nv, sqrtf(a), &ta, &tb);
        e1w = fmaxf(ta + tb, 1e-3f);
    }
    for (int c = 0; c < 3; c++) {
        const float f = s->f0[c] + (s->f90 - s->f0[c]) * fw;
        const float comp = e1w > 0.0f ? 1.0f + s->f0[c] * (1.0f / e1w - 1.0f) : s->comp[c];
        const float brdf = s->diffuse[c] * (1.0f / EVR_PI) + dv * f * comp;
        acc[c] += e_rgb[c] * nl * brdf;
    }
}

/* Radiance leaving s towards wo (RGB) from the lights' sum acc (evr_material_add_light), the
 * ambient environment (uniform radiance `ambient`, which the camera does not see directly but
 * surfaces reflect) and emission. The ambient light the specular lobe reflects is left out
 * when the caller traces the reflection as a ray (reflect_traced), and the ambient light
 * transmitted when it traces the refraction (transmit_traced). BLEND's coverage is the
 * caller's (evr_surface.opacity). An unlit surface shows its base colour. */
EVR_HD static inline void evr_material_radiance(const evr_surface *s, evr_v3 wo, const float acc[3],
                                                float ambient, int reflect_traced,
                                                int transmit_traced, float rgb[3])
{
    (void)wo;
    for (int c = 0; c < 3; c++) {
        if (s->unlit) {
            rgb[c] = s->albedo[c];
            continue;
        }
        float env = s->diffuse[c] * s->occlusion;
        if (!reflect_traced) env += s->spec_albedo[c] * s->occlusion;
        if (!transmit_traced) env += s->transmit[c];
        rgb[c] = acc[c] + ambient * env + s->emissive[c];
    }
}

/* Whether s reflects along one mirror ray (smooth enough, and reflecting anything). */
EVR_HD static inline int evr_material_mirror(const evr_surface *s)
{
    return !s->unlit && s->rough < EVR_MIRROR_ROUGHNESS;
}

/* Whether s transmits anything (the refraction is always traced as one ray). */
EVR_HD static inline int evr_material_transmits(const evr_surface *s)
{
    return !s->unlit && (s->transmit[0] > 0.0f || s->transmit[1] > 0.0f || s->transmit[2] > 0.0f);
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
}

#endif
