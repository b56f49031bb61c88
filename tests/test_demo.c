/* The built-in scenes: each is a valid GLB (header, chunk layout) that Assimp imports, from
 * memory and from a file, with the expected meshes, materials, textures, camera, lights and
 * animation (the blink scene's bones and morph targets too); and it loads through
 * evr_demo_load. */
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "evray.h"
#include "scene/scene.h"

typedef struct {
    const char *name;
    const char *meshes[12]; /* NULL-terminated */
    const char *materials[12];
    int min_textures;
    const char *textured_material; /* a material whose base colour comes from an embedded PNG */
    const char *camera;
    float camera_aspect, camera_znear;
    double camera_pos[3], camera_target[3];
    const char *light;
    int light_type;
    const char *animated[4]; /* nodes with animation channels */
    double anim_length;      /* seconds */
    unsigned min_triangles, max_triangles;
} expectation;

static const expectation expected[] = {
    {"eye",
     {"sclera", "cornea", "iris", "pupil", "upper_lid", "lower_lid", "upper_lashes", "lower_lashes",
      "skin", "orbit", NULL},
     {"sclera", "cornea", "iris", "pupil", "upper_eyelid", "lower_eyelid", "upper_lashes",
      "lower_lashes", "skin", "orbit", NULL},
     7,
     "iris",
     "eye_camera",
     4.0f / 3.0f,
     0.001f,
     {0.0, -0.010, 0.040},
     {0.0, 0.0, 0.0},
     "ir_led",
     aiLightSource_POINT,
     {"eyeball", "upper_lid", "lower_lid", NULL},
     30.0,
     10000,
     40000},
    {"eye-drift",
     {"sclera", "cornea", "iris", "pupil", "upper_lid", "lower_lid", "upper_lashes", "lower_lashes",
      "skin", "orbit", NULL},
     {"sclera", "cornea", "iris", "pupil", "upper_eyelid", "lower_eyelid", "upper_lashes",
      "lower_lashes", "skin", "orbit", NULL},
     7,
     "iris",
     "eye_camera",
     4.0f / 3.0f,
     0.001f,
     {0.0, -0.010, 0.040},
     {0.0, 0.0, 0.0},
     "ir_led",
     aiLightSource_POINT,
     {"eyeball", "upper_lid", "lower_lid", NULL},
     30.0,
     10000,
     40000},
    {"square",
     {"background", "square", NULL},
     {"background", "square", NULL},
     0,
     NULL,
     "square_camera",
     1.0f,
     0.1f,
     {0.0, 0.0, 4.0},
     {0.0, 0.0, 0.0},
     "lamp",
     aiLightSource_POINT,
     {"square", NULL},
     2.0,
     4,
     4},
    {"disk",
     {"white_sectors", "black_sectors", "background", NULL},
     {"white", "black", "background", NULL},
     0,
     NULL,
     "disk_camera",
     4.0f / 3.0f,
     0.05f,
     {0.0, 0.0, 2.0},
     {0.0, 0.0, 0.0},
     "lamp",
     aiLightSource_POINT,
     {"disk", NULL},
     2.0,
     258,
     258},
    {"cornell",
     {"floor", "ceiling", "back_wall", "left_wall", "right_wall", "tall_box", "short_box", NULL},
     {"white", "red", "green", "light", NULL},
     0,
     NULL,
     "cornell_camera",
     1.0f,
     0.05f,
     {0.0, 0.5, 1.9},
     {0.0, 0.5, 0.0},
     "ceiling_light",
     aiLightSource_POINT,
     {"short_box", NULL},
     2.0,
     36,
     36},
    {"cornell-still", /* the same room; the short box's animation holds it still */
     {"floor", "ceiling", "back_wall", "left_wall", "right_wall", "tall_box", "short_box", NULL},
     {"white", "red", "green", "light", NULL},
     0,
     NULL,
     "cornell_camera",
     1.0f,
     0.05f,
     {0.0, 0.5, 1.9},
     {0.0, 0.5, 0.0},
     "ceiling_light",
     aiLightSource_POINT,
     {"short_box", NULL},
     2.0,
     36,
     36},
    {"cornell-bleed", /* white side walls; the red short box slides along the right wall */
     {"floor", "ceiling", "back_wall", "left_wall", "right_wall", "tall_box", "short_box", NULL},
     {"white", "red", "light", NULL},
     0,
     NULL,
     "cornell_camera",
     1.0f,
     0.05f,
     {0.0, 0.5, 1.9},
     {0.0, 0.5, 0.0},
     "ceiling_light",
     aiLightSource_POINT,
     {"short_box", NULL},
     2.0,
     36,
     36},
    {"city", /* 12 building meshes, each stored once (4096 nodes share them), and the ground */
     {"building_00", "building_07", "building_11", "ground", NULL},
     {"facade_00", "facade_11", "asphalt", NULL},
     0,
     NULL,
     "city_camera",
     4.0f / 3.0f,
     0.5f,
     {0.0, 34.0, 100.0},
     {4.854101966, 25.0, 40.0},
     "sun",
     aiLightSource_DIRECTIONAL,
     {"city_camera", NULL},
     5.0,
     40000,
     80000},
    {"blink", /* the eye's parts, lids deformed by morph targets, a skinned finger */
     {"sclera", "cornea", "iris", "pupil", "upper_lid", "lower_lid", "upper_lashes", "lower_lashes",
      "skin", "orbit", "finger", NULL},
     {"sclera", "cornea", "iris", "pupil", "upper_eyelid", "lower_eyelid", "upper_lashes",
      "lower_lashes", "skin", "finger", "orbit", NULL},
     8,
     "finger",
     "blink_camera",
     16.0f / 9.0f,
     0.001f,
     {0.012, 0.0, 0.130},
     {0.012, 0.0, 0.0},
     "lamp",
     aiLightSource_POINT,
     {"finger_mcp", "finger_pip", "finger_dip", NULL},
     3.6,
     40000,
     45000},
};

static uint32_t rd_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void check_glb_layout(const unsigned char *b, size_t n)
{
    uint32_t json_len, bin_len;
    CHECK(n >= 28 && n % 4 == 0);
    if (n < 28) return;
    CHECK(memcmp(b, "glTF", 4) == 0);
    CHECK(rd_u32(b + 4) == 2);
    CHECK(rd_u32(b + 8) == n);
    json_len = rd_u32(b + 12);
    CHECK(memcmp(b + 16, "JSON", 4) == 0);
    CHECK(json_len % 4 == 0 && 20 + (size_t)json_len <= n);
    if (20 + (size_t)json_len > n) return;
    CHECK(b[20] == '{');
    CHECK(b[20 + json_len - 1] == '}' || b[20 + json_len - 1] == ' ');
    {
        char *json = malloc(json_len + 1);
        if (json) {
            memcpy(json, b + 20, json_len);
            json[json_len] = 0;
            CHECK(strstr(json, "\"version\":\"2.0\"") != NULL);
            if (strstr(json, "KHR_lights_punctual")) { /* listed first when used */
                CHECK(strstr(json, "\"extensionsUsed\":[\"KHR_lights_punctual\"") != NULL);
            }
            free(json);
        }
    }
    if (20 + (size_t)json_len == n) return; /* no BIN chunk */
    CHECK(20 + (size_t)json_len + 8 <= n);
    bin_len = rd_u32(b + 20 + json_len);
    CHECK(memcmp(b + 24 + json_len, "BIN\0", 4) == 0);
    CHECK(bin_len % 4 == 0);
    CHECK(28 + (size_t)json_len + bin_len == n);
}

static const struct aiNode *find_node(const struct aiNode *n, const char *name)
{
    unsigned i;
    if (strcmp(n->mName.data, name) == 0) return n;
    for (i = 0; i < n->mNumChildren; i++) {
        const struct aiNode *r = find_node(n->mChildren[i], name);
        if (r) return r;
    }
    return NULL;
}

static struct aiMatrix4x4 world_of(const struct aiNode *n)
{
    struct aiMatrix4x4 m = n->mTransformation;
    for (n = n->mParent; n; n = n->mParent) {
        struct aiMatrix4x4 p = n->mTransformation;
        aiMultiplyMatrix4(&p, &m);
        m = p;
    }
    return m;
}

static const struct aiMaterial *find_material(const struct aiScene *s, const char *name)
{
    unsigned i;
    for (i = 0; i < s->mNumMaterials; i++) {
        struct aiString str;
        if (aiGetMaterialString(s->mMaterials[i], AI_MATKEY_NAME, &str) == aiReturn_SUCCESS &&
            strcmp(str.data, name) == 0)
            return s->mMaterials[i];
    }
    return NULL;
}

static void check_scene(const struct aiScene *s, const expectation *e, int full)
{
    unsigned i, tris = 0;
    int k;
    CHECK(s != NULL);
    if (!s) return;
    for (k = 0; e->meshes[k]; k++) {
        int found = 0;
        for (i = 0; i < s->mNumMeshes; i++)
            found |= strcmp(s->mMeshes[i]->mName.data, e->meshes[k]) == 0;
        if (!found) fprintf(stderr, "%s: no mesh %s\n", e->name, e->meshes[k]);
        CHECK(found);
    }
    for (i = 0; i < s->mNumMeshes; i++) {
        const struct aiMesh *m = s->mMeshes[i];
        tris += m->mNumFaces;
        CHECK(m->mNormals != NULL);
        CHECK(m->mPrimitiveTypes == aiPrimitiveType_TRIANGLE);
    }
    if (tris < e->min_triangles || tris > e->max_triangles)
        fprintf(stderr, "%s: %u triangles\n", e->name, tris);
    CHECK(tris >= e->min_triangles && tris <= e->max_triangles);
    if (!full) return;

    for (k = 0; e->materials[k]; k++) CHECK(find_material(s, e->materials[k]) != NULL);
    CHECK((int)s->mNumTextures >= e->min_textures);
    for (i = 0; i < s->mNumTextures; i++) {
        CHECK(s->mTextures[i]->mHeight == 0); /* compressed (embedded PNG) */
        CHECK(strcmp(s->mTextures[i]->achFormatHint, "png") == 0);
        CHECK(s->mTextures[i]->mWidth > 8 && memcmp(s->mTextures[i]->pcData, "\x89PNG", 4) == 0);
    }
    if (e->textured_material) {
        const struct aiMaterial *m = find_material(s, e->textured_material);
        struct aiString path;
        CHECK(m != NULL);
        if (m) {
            CHECK(aiGetMaterialTexture(m, aiTextureType_DIFFUSE, 0, &path, NULL, NULL, NULL, NULL,
                                       NULL, NULL) == aiReturn_SUCCESS);
            CHECK(path.data[0] == '*' && atoi(path.data + 1) < (int)s->mNumTextures);
        }
    }

    /* camera: name, lens, and the world pose of its node (looking along its -Z at the target) */
    CHECK(s->mNumCameras == 1);
    if (s->mNumCameras == 1) {
        const struct aiCamera *c = s->mCameras[0];
        const struct aiNode *n = find_node(s->mRootNode, c->mName.data);
        CHECK(strcmp(c->mName.data, e->camera) == 0);
        CHECK_NEAR(c->mAspect, e->camera_aspect, 1e-6);
        CHECK_NEAR(c->mClipPlaneNear, e->camera_znear, 1e-9);
        CHECK(n != NULL);
        if (n) {
            struct aiMatrix4x4 w = world_of(n);
            double d[3], l;
            CHECK_NEAR(w.a4, e->camera_pos[0], 1e-6);
            CHECK_NEAR(w.b4, e->camera_pos[1], 1e-6);
            CHECK_NEAR(w.c4, e->camera_pos[2], 1e-6);
            d[0] = e->camera_target[0] - e->camera_pos[0];
            d[1] = e->camera_target[1] - e->camera_pos[1];
            d[2] = e->camera_target[2] - e->camera_pos[2];
            l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            CHECK_NEAR(-w.a3, d[0] / l, 1e-5);
            CHECK_NEAR(-w.b3, d[1] / l, 1e-5);
            CHECK_NEAR(-w.c3, d[2] / l, 1e-5);
            CHECK(w.b2 > 0.9); /* up stays up */
        }
    }
    CHECK(s->mNumLights == 1);
    if (s->mNumLights == 1) {
        CHECK(strcmp(s->mLights[0]->mName.data, e->light) == 0);
        CHECK((int)s->mLights[0]->mType == e->light_type);
        CHECK(s->mLights[0]->mColorDiffuse.r > 0.0f);
    }

    /* animation: every expected node has keys, all times within [0, length], reaching the end */
    CHECK(s->mNumAnimations == 1);
    if (s->mNumAnimations == 1) {
        const struct aiAnimation *a = s->mAnimations[0];
        double tps = a->mTicksPerSecond > 0.0 ? a->mTicksPerSecond : 1.0;
        CHECK_NEAR(a->mDuration / tps, e->anim_length, 1e-6);
        for (k = 0; e->animated[k]; k++) {
            const struct aiNodeAnim *na = NULL;
            for (i = 0; i < a->mNumChannels; i++)
                if (strcmp(a->mChannels[i]->mNodeName.data, e->animated[k]) == 0)
                    na = a->mChannels[i];
            CHECK(na != NULL);
            if (!na) continue;
            CHECK(na->mNumPositionKeys > 0 && na->mNumRotationKeys > 0 && na->mNumScalingKeys > 0);
            for (i = 0; i < na->mNumRotationKeys; i++) {
                double t = na->mRotationKeys[i].mTime / tps;
                CHECK(t >= 0.0 && t <= e->anim_length + 1e-6);
                if (i) CHECK(na->mRotationKeys[i].mTime > na->mRotationKeys[i - 1].mTime);
            }
            for (i = 0; i < na->mNumPositionKeys; i++) {
                double t = na->mPositionKeys[i].mTime / tps;
                CHECK(t >= 0.0 && t <= e->anim_length + 1e-6);
            }
        }
    }
}

static const struct aiMesh *find_mesh(const struct aiScene *s, const char *name)
{
    unsigned i;
    for (i = 0; i < s->mNumMeshes; i++)
        if (strcmp(s->mMeshes[i]->mName.data, name) == 0) return s->mMeshes[i];
    return NULL;
}

/* The blink scene's deformers as Assimp reads them: the finger's three bones (each vertex on at
 * most two, weights summing to 1), the lids' morph targets (2 and 1) and the weight channels of
 * the lids and their lashes,
 * keyed 0 at both ends (the animation loops). */
static void check_blink_deformers(const struct aiScene *s)
{
    const struct aiMesh *finger = find_mesh(s, "finger"), *up = find_mesh(s, "upper_lid"),
                        *lo = find_mesh(s, "lower_lid");
    unsigned i, k;
    CHECK(finger && up && lo);
    if (!finger || !up || !lo) return;
    CHECK(finger->mNumBones == 3);
    if (finger->mNumBones == 3) {
        double *sum = calloc(finger->mNumVertices, sizeof *sum);
        unsigned *count = calloc(finger->mNumVertices, sizeof *count);
        static const char *const bones[3] = {"finger_mcp", "finger_pip", "finger_dip"};
        CHECK(sum && count);
        for (i = 0; sum && count && i < 3; i++) {
            const struct aiBone *b = finger->mBones[i];
            int known = 0;
            for (k = 0; k < 3; k++) known |= strcmp(b->mName.data, bones[k]) == 0;
            CHECK(known);
            for (k = 0; k < b->mNumWeights; k++) {
                sum[b->mWeights[k].mVertexId] += b->mWeights[k].mWeight;
                count[b->mWeights[k].mVertexId] += b->mWeights[k].mWeight > 0.0f;
            }
        }
        for (i = 0; sum && count && i < finger->mNumVertices; i++) {
            CHECK_NEAR(sum[i], 1.0, 1e-5);
            CHECK(count[i] >= 1 && count[i] <= 2);
        }
        free(sum);
        free(count);
    }
    CHECK(up->mNumAnimMeshes == 2 && lo->mNumAnimMeshes == 1);
    /* the lids and their lashes */
    CHECK(s->mNumAnimations == 1 && s->mAnimations[0]->mNumMorphMeshChannels == 4);
    for (i = 0; s->mNumAnimations == 1 && i < s->mAnimations[0]->mNumMorphMeshChannels; i++) {
        const struct aiMeshMorphAnim *c = s->mAnimations[0]->mMorphMeshChannels[i];
        CHECK(c->mNumKeys > 100);
        if (c->mNumKeys < 2) continue;
        for (k = 0; k < c->mKeys[0].mNumValuesAndWeights; k++) {
            CHECK(c->mKeys[0].mWeights[k] == 0.0);
            CHECK(c->mKeys[c->mNumKeys - 1].mWeights[k] == 0.0);
        }
    }
}

/* Facts of the square scene that tests elsewhere derive analytic results from. */
static void check_square_numbers(const struct aiScene *s)
{
    const struct aiMaterial *bg = find_material(s, "background"), *sq = find_material(s, "square");
    struct aiColor4D cb, cs;
    const struct aiNodeAnim *na;
    CHECK(bg && sq);
    if (!bg || !sq || !s->mNumAnimations || !s->mNumCameras) return;
    CHECK(aiGetMaterialColor(bg, "$clr.base", 0, 0, &cb) == aiReturn_SUCCESS);
    CHECK(aiGetMaterialColor(sq, "$clr.base", 0, 0, &cs) == aiReturn_SUCCESS);
    CHECK_NEAR(cb.r, 0.1, 1e-7);
    CHECK_NEAR(log(cs.r / cb.r), 2.0, 1e-6);
    CHECK_NEAR(cs.g, cs.r, 0.0);
    na = s->mAnimations[0]->mChannels[0];
    CHECK(na->mNumPositionKeys == 2);
    if (na->mNumPositionKeys == 2) {
        double tps =
            s->mAnimations[0]->mTicksPerSecond > 0.0 ? s->mAnimations[0]->mTicksPerSecond : 1.0;
        CHECK_NEAR(na->mPositionKeys[0].mTime / tps, 0.0, 1e-9);
        CHECK_NEAR(na->mPositionKeys[1].mTime / tps, 2.0, 1e-6);
        CHECK_NEAR(na->mPositionKeys[0].mValue.x, -1.0, 1e-7);
        CHECK_NEAR(na->mPositionKeys[1].mValue.x, 1.0, 1e-7);
        CHECK_NEAR(na->mPositionKeys[0].mValue.z, 0.01, 1e-7);
    }
    /* glTF through Assimp: mHorizontalFOV = yfov * aspect, aspect 1 here */
    CHECK_NEAR(s->mCameras[0]->mHorizontalFOV, 2.0 * atan(0.25), 1e-6);
    CHECK_NEAR(s->mLights[0]->mColorDiffuse.r, 16.0 * 3.14159265,
               1e-4); /* the lamp at the camera */
}

int main(void)
{
    const char *const *names = evr_demo_names();
    size_t i;
    int k, count = 0;
    evr_error err;
    void *glb = NULL;
    size_t n = 0;

    CHECK(names != NULL);
    for (k = 0; names && names[k]; k++) count++;
    CHECK(count == (int)(sizeof expected / sizeof expected[0]));
    CHECK(evr_demo_has_variants("eye") == 1 && evr_demo_has_variants("eye-drift") == 1);
    CHECK(evr_demo_has_variants("square") == 0 && evr_demo_has_variants("city") == 0);
    CHECK(evr_demo_has_variants("no-such-scene") == 0 && evr_demo_has_variants(NULL) == 0);

    for (i = 0; i < sizeof expected / sizeof expected[0]; i++) {
        const expectation *e = &expected[i];
        const struct aiScene *s;
        char path[512];
        const char *tmp = getenv("TMPDIR");
        FILE *f;
        int listed = 0;
        for (k = 0; names[k]; k++) listed |= strcmp(names[k], e->name) == 0;
        CHECK(listed);

        err.msg[0] = 0;
        CHECK_OK(evr_demo_glb(e->name, &glb, &n, &err));
        if (!glb) {
            fprintf(stderr, "%s: %s\n", e->name, err.msg);
            continue;
        }
        check_glb_layout(glb, n);

        /* deterministic: the same bytes every time */
        {
            void *again = NULL;
            size_t n2 = 0;
            CHECK_OK(evr_demo_glb(e->name, &again, &n2, &err));
            CHECK(again && n2 == n && memcmp(again, glb, n) == 0);
            free(again);
        }

        s = aiImportFileFromMemory(glb, (unsigned)n, aiProcess_Triangulate, "glb");
        if (!s) fprintf(stderr, "%s: Assimp: %s\n", e->name, aiGetErrorString());
        check_scene(s, e, 1);
        if (s && strcmp(e->name, "square") == 0) check_square_numbers(s);
        if (s && strcmp(e->name, "blink") == 0) check_blink_deformers(s);
        aiReleaseImport(s);

        /* the same through a file, as `evray demo --export` writes it */
        snprintf(path, sizeof path, "%s/evray_test_demo_%ld_%s.glb", tmp && *tmp ? tmp : "/tmp",
                 (long)getpid(), e->name);
        f = fopen(path, "wb");
        CHECK(f != NULL);
        if (f) {
            CHECK(fwrite(glb, 1, n, f) == n);
            CHECK(fclose(f) == 0);
            s = aiImportFile(path, aiProcess_Triangulate);
            if (!s) fprintf(stderr, "%s: Assimp (file): %s\n", e->name, aiGetErrorString());
            check_scene(s, e, 0);
            aiReleaseImport(s);
            CHECK(remove(path) == 0);
        }
        free(glb);
        glb = NULL;

        /* and through evray's own importer */
        {
            evr_scene *scene = NULL;
            err.msg[0] = 0;
            CHECK_OK(evr_demo_load(e->name, &scene, &err));
            if (!scene) {
                fprintf(stderr, "%s: evr_demo_load: %s\n", e->name, err.msg);
            } else {
                CHECK(scene->num_cameras >= 1);
                CHECK(scene->num_lights == 1);
                CHECK_NEAR(scene->anim_end, e->anim_length, 1e-3);
                evr_scene_release(scene);
            }
        }
    }

    /* unknown names */
    err.msg[0] = 0;
    CHECK(evr_demo_glb("no-such-scene", &glb, &n, &err) == EVR_ERR_ARG);
    CHECK(glb == NULL && n == 0);
    CHECK(strstr(err.msg, "no-such-scene") && strstr(err.msg, "eye") && strstr(err.msg, "square"));
    {
        evr_scene *scene = (evr_scene *)&err;
        CHECK(evr_demo_load("no-such-scene", &scene, &err) == EVR_ERR_ARG);
        CHECK(scene == NULL);
    }
    CHECK(evr_demo_glb(NULL, &glb, &n, &err) == EVR_ERR_ARG);
    return check_report("test_demo");
}
