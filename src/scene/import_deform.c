/* Skins, morph targets, the nodes' morph weights and their curves, for every format through
 * Assimp: bones (aiBone: the joint node's name, mOffsetMatrix the inverse bind matrix, the
 * weights), anim meshes (aiAnimMesh: absolute positions and normals, mWeight the default
 * weight) and morph channels (aiMeshMorphAnim), with the glTF JSON where Assimp 5.2 drops
 * something (quirks (f) to (h) in import.c). Weights are normalized per vertex; a vertex without
 * weight, a bone naming no node or an anim mesh of another size is an error naming the mesh. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

static evr_status import_skin(importer *im, int mi)
{
    const struct aiMesh *am = im->ai->mMeshes[mi];
    evr_mesh *m = &im->s->meshes[mi];
    const unsigned nv = am->mNumVertices, nb = am->mNumBones;
    int *count = NULL, influences = 0;
    evr_skin *sk = NULL;
    unsigned b, w, v;
    evr_status st = EVR_ERR_NOMEM;

    if (nb > 65535)
        return evr_import_fail(im->err, EVR_ERR_FORMAT,
                               "mesh '%s' has %u joints (evray takes at most 65535)", m->name, nb);
    count = calloc((size_t)nv + 1, sizeof *count);
    sk = calloc(1, sizeof *sk);
    if (!count || !sk) goto fail;
    sk->num_joints = (int)nb;
    sk->joint_nodes = malloc(((size_t)nb + 1) * sizeof *sk->joint_nodes);
    sk->inverse_bind = malloc(((size_t)nb + 1) * sizeof *sk->inverse_bind);
    if (!sk->joint_nodes || !sk->inverse_bind) goto fail;
    for (b = 0; b < nb; b++) {
        const struct aiBone *bone = am->mBones[b];
        int node = bone ? evr_import_find_node(im, bone->mName.data) : -1;
        if (node < 0) {
            st = evr_import_fail(im->err, EVR_ERR_FORMAT,
                                 "mesh '%s': joint %u ('%s') names no node of the scene", m->name,
                                 b, bone ? bone->mName.data : "");
            goto fail;
        }
        if (evr_import_name_count(im, bone->mName.data) > 1)
            evr_import_warn(im, "mesh '%s': joint name '%s' names %d nodes; the first is used",
                            m->name, bone->mName.data, evr_import_name_count(im, bone->mName.data));
        sk->joint_nodes[b] = node;
        sk->inverse_bind[b] = evr_import_m34(&bone->mOffsetMatrix);
        for (w = 0; w < bone->mNumWeights; w++) {
            const struct aiVertexWeight *vw = &bone->mWeights[w];
            if (vw->mVertexId >= nv) {
                st = evr_import_fail(im->err, EVR_ERR_FORMAT,
                                     "mesh '%s': joint '%s' weighs vertex %u of %u", m->name,
                                     bone->mName.data, vw->mVertexId, nv);
                goto fail;
            }
            if (!(vw->mWeight >= 0.0f) || !isfinite(vw->mWeight)) {
                st = evr_import_fail(im->err, EVR_ERR_FORMAT,
                                     "mesh '%s': vertex %u has a negative or non-finite weight "
                                     "(%g) for joint '%s'",
                                     m->name, vw->mVertexId, (double)vw->mWeight, bone->mName.data);
                goto fail;
            }
            /* Assimp's glTF importer gives a bone without weights one of 0 (vertex 0) */
            if (vw->mWeight > 0.0f && ++count[vw->mVertexId] > influences)
                influences = count[vw->mVertexId];
        }
    }
    if (influences == 0) influences = 1; /* every vertex fails below */
    sk->influences = influences;
    sk->joints = calloc((size_t)nv * (size_t)influences + 1, sizeof *sk->joints);
    sk->weights = calloc((size_t)nv * (size_t)influences + 1, sizeof *sk->weights);
    if (!sk->joints || !sk->weights) goto fail;
    memset(count, 0, ((size_t)nv + 1) * sizeof *count);
    for (b = 0; b < nb; b++)
        for (w = 0; w < am->mBones[b]->mNumWeights; w++) {
            const struct aiVertexWeight *vw = &am->mBones[b]->mWeights[w];
            size_t at;
            if (!(vw->mWeight > 0.0f)) continue;
            at = (size_t)vw->mVertexId * (size_t)influences + (size_t)count[vw->mVertexId]++;
            sk->joints[at] = (uint16_t)b;
            sk->weights[at] = vw->mWeight;
        }
    for (v = 0; v < nv; v++) { /* normalized: the weights sum to 1 */
        float *wv = sk->weights + (size_t)v * (size_t)influences;
        double sum = 0.0;
        int k;
        for (k = 0; k < influences; k++) sum += wv[k];
        if (!(sum > 0.0)) {
            st = evr_import_fail(im->err, EVR_ERR_FORMAT,
                                 "mesh '%s': vertex %u has no joint weight (all zero)", m->name, v);
            goto fail;
        }
        for (k = 0; k < influences; k++) wv[k] = (float)(wv[k] / sum);
    }
    free(count);
    m->skin = sk;
    return EVR_OK;
fail:
    if (st == EVR_ERR_NOMEM) evr_import_fail(im->err, st, "out of memory reading skins");
    free(count);
    if (sk) {
        free(sk->joint_nodes);
        free(sk->inverse_bind);
        free(sk->joints);
        free(sk->weights);
        free(sk);
    }
    return st;
}

/* Morph targets as deltas: Assimp keeps each target's absolute positions and normals (quirk
 * (g)), except where the mesh says its targets are relative (Collada's RELATIVE morphs, whose
 * target geometry holds the offsets). */
static evr_status import_morph(importer *im, int mi)
{
    const struct aiMesh *am = im->ai->mMeshes[mi];
    evr_mesh *m = &im->s->meshes[mi];
    const unsigned nv = am->mNumVertices, nt = am->mNumAnimMeshes;
    evr_morph *mo = calloc(1, sizeof *mo);
    unsigned t, v;
    int normals = 0;
    const float keep = am->mMethod == aiMorphingMethod_MORPH_RELATIVE ? 0.0f : 1.0f;
    if (!mo) goto nomem;
    for (t = 0; t < nt; t++) {
        const struct aiAnimMesh *an = am->mAnimMeshes[t];
        if (!an || an->mNumVertices != nv) {
            free(mo);
            return evr_import_fail(im->err, EVR_ERR_FORMAT,
                                   "mesh '%s': morph target %u has %u vertices for the mesh's %u",
                                   m->name, t, an ? an->mNumVertices : 0, nv);
        }
        if (an->mNormals && am->mNormals) normals = 1;
    }
    mo->num_targets = (int)nt;
    mo->d_positions = calloc((size_t)nt * nv * 3 + 1, sizeof *mo->d_positions);
    mo->default_weights = calloc((size_t)nt + 1, sizeof *mo->default_weights);
    if (normals) mo->d_normals = calloc((size_t)nt * nv * 3 + 1, sizeof *mo->d_normals);
    if (!mo->d_positions || !mo->default_weights || (normals && !mo->d_normals)) goto nomem;
    for (t = 0; t < nt; t++) {
        const struct aiAnimMesh *an = am->mAnimMeshes[t];
        float *dp = mo->d_positions + (size_t)t * nv * 3;
        mo->default_weights[t] = isfinite(an->mWeight) ? an->mWeight : 0.0f;
        for (v = 0; an->mVertices && v < nv; v++) {
            dp[3 * v] = an->mVertices[v].x - keep * am->mVertices[v].x;
            dp[3 * v + 1] = an->mVertices[v].y - keep * am->mVertices[v].y;
            dp[3 * v + 2] = an->mVertices[v].z - keep * am->mVertices[v].z;
        }
        if (normals && an->mNormals) {
            float *dn = mo->d_normals + (size_t)t * nv * 3;
            for (v = 0; v < nv; v++) {
                dn[3 * v] = an->mNormals[v].x - keep * am->mNormals[v].x;
                dn[3 * v + 1] = an->mNormals[v].y - keep * am->mNormals[v].y;
                dn[3 * v + 2] = an->mNormals[v].z - keep * am->mNormals[v].z;
            }
        }
    }
    m->morph = mo;
    return EVR_OK;
nomem:
    if (mo) {
        free(mo->d_positions);
        free(mo->d_normals);
        free(mo->default_weights);
        free(mo);
    }
    return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading morph targets");
}

/* The glTF node whose Assimp name is `name`, or -1. */
static int side_node(const importer *im, const char *name)
{
    int i;
    for (i = 0; i < im->side.num_nodes; i++)
        if (!strcmp(im->side.node_names[i], name)) return i;
    return -1;
}

/* Each node placing a morphing mesh gets as many weights as its meshes have targets, at rest
 * the node's own (glTF node.weights, which Assimp drops: quirk (h)) or else its first morphing
 * mesh's defaults. */
static evr_status node_weights(importer *im)
{
    evr_scene *s = im->s;
    int i;
    for (i = 0; i < s->num_instances; i++) {
        const evr_morph *mo = s->meshes[s->instances[i].mesh].morph;
        evr_node *n = &s->nodes[s->instances[i].node];
        if (mo && mo->num_targets > n->num_weights) n->num_weights = mo->num_targets;
    }
    for (i = 0; i < s->num_nodes; i++) {
        evr_node *n = &s->nodes[i];
        if (n->num_weights > 0 && !(n->weights = calloc((size_t)n->num_weights, sizeof(float))))
            return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading morph weights");
    }
    for (i = s->num_instances; i-- > 0;) { /* the first mesh's defaults last: they stay */
        const evr_morph *mo = s->meshes[s->instances[i].mesh].morph;
        evr_node *n = &s->nodes[s->instances[i].node];
        if (mo) memcpy(n->weights, mo->default_weights, sizeof(float) * (size_t)mo->num_targets);
    }
    if (!im->have_side) return EVR_OK;
    for (i = 0; i < s->num_nodes; i++) {
        evr_node *n = &s->nodes[i];
        int g = n->num_weights > 0 ? side_node(im, im->ai_nodes[i]->mName.data) : -1;
        if (g < 0 || im->side.node_num_weights[g] <= 0) continue;
        memcpy(n->weights, im->side.node_weights[g],
               sizeof(float) * (size_t)(im->side.node_num_weights[g] < n->num_weights
                                            ? im->side.node_num_weights[g]
                                            : n->num_weights));
    }
    return EVR_OK;
}

/* The nodes a morph channel drives: the node of that name (glTF), else of the name before a
 * '*' suffix (Assimp's "name*N" of a mesh's Nth channel), else those placing meshes of that
 * name (aiMeshMorphAnim documents a mesh name). Writes their indices into out; returns how many. */
static int channel_nodes(const importer *im, const char *name, int *out, int cap)
{
    const evr_scene *s = im->s;
    char base[1024];
    const char *star = strrchr(name, '*');
    int n = 0, i, pass;
    for (pass = 0; pass < 2; pass++) {
        const char *want = name;
        int node;
        if (pass == 1) {
            if (!star) break;
            evr_import_copy_name(base,
                                 (size_t)(star - name) + 1 < sizeof base ? (size_t)(star - name) + 1
                                                                         : sizeof base,
                                 name);
            want = base;
        }
        node = evr_import_find_node(im, want);
        if (node >= 0 && s->nodes[node].num_weights > 0) {
            out[0] = node;
            return 1;
        }
        for (i = 0; i < s->num_instances && n < cap; i++) {
            int mi = s->instances[i].mesh, k, dup = 0;
            if (!s->meshes[mi].morph || strcmp(im->ai->mMeshes[mi]->mName.data, want)) continue;
            for (k = 0; k < n; k++) dup |= out[k] == s->instances[i].node;
            if (!dup) out[n++] = s->instances[i].node;
        }
        if (n) return n;
    }
    return 0;
}

static evr_status weight_curve(importer *im, const struct aiMeshMorphAnim *mc, unsigned a,
                               double tps, int ni, int side_ok)
{
    evr_node *n = &im->s->nodes[ni];
    evr_curve *c = &n->w_curve;
    const int d = n->num_weights;
    unsigned k, j;
    int interp = GL_LINEAR, rest = 1;
    c->times = malloc(((size_t)mc->mNumKeys + 1) * sizeof *c->times);
    c->values = malloc(((size_t)mc->mNumKeys * (size_t)d + 1) * sizeof *c->values);
    if (!c->times || !c->values) {
        evr_import_curve_free(c);
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading morph weights");
    }
    c->num_keys = (int)mc->mNumKeys;
    for (k = 0; k < mc->mNumKeys; k++) {
        const struct aiMeshMorphKey *key = &mc->mKeys[k];
        float *v = c->values + (size_t)k * (size_t)d;
        /* quirk (a): glTF's keys are in milliseconds, like the node keys */
        c->times[k] = key->mTime / tps;
        memcpy(v, n->weights, sizeof *v * (size_t)d); /* targets a key leaves out keep rest */
        for (j = 0; j < key->mNumValuesAndWeights; j++)
            if (key->mValues[j] < (unsigned)d && isfinite(key->mWeights[j]))
                v[key->mValues[j]] = (float)key->mWeights[j];
        if (memcmp(v, n->weights, sizeof *v * (size_t)d)) rest = 0;
    }
    evr_import_curve_sort(c, d);
    if (im->have_side) {
        interp = evr_gltf_side_interp(&im->side, side_ok ? (int)a : -1,
                                      im->ai_nodes[ni]->mName.data, PATH_W);
        if (interp == GL_CUBIC)
            evr_import_warn(im,
                            "node '%s': CUBICSPLINE morph weights are interpolated linearly "
                            "between keys (their tangents are ignored)",
                            n->name);
    }
    c->interp = interp == GL_STEP ? EVR_INTERP_STEP : EVR_INTERP_LINEAR;
    if (rest) evr_import_curve_free(c); /* it only repeats the rest weights */
    return EVR_OK;
}

/* Morph weight curves from every played clip's morph channels (the first clip wins a node). */
static evr_status weight_curves(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    int side_ok = im->have_side && im->side.num_anims == (int)ai->mNumAnimations;
    int *nodes = malloc(((size_t)s->num_nodes + 1) * sizeof *nodes), i, any = 0;
    double t0 = INFINITY, t1 = -INFINITY;
    unsigned a, ch;
    if (!nodes) return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading animations");
    for (a = 0; a < ai->mNumAnimations; a++) {
        const struct aiAnimation *an = ai->mAnimations[a];
        double tps = an->mTicksPerSecond > 0.0 ? an->mTicksPerSecond : 25.0;
        if (im->clip_played && !im->clip_played[a]) continue;
        for (ch = 0; ch < an->mNumMorphMeshChannels; ch++) {
            const struct aiMeshMorphAnim *mc = an->mMorphMeshChannels[ch];
            int nn = channel_nodes(im, mc->mName.data, nodes, s->num_nodes), k;
            if (nn == 0) {
                evr_import_warn(im, "morph weight channel '%s' drives no morphing mesh: ignored",
                                mc->mName.data);
                continue;
            }
            for (k = 0; k < nn; k++) {
                evr_status st;
                if (s->nodes[nodes[k]].w_curve.num_keys > 0 || mc->mNumKeys == 0) continue;
                if ((st = weight_curve(im, mc, a, tps, nodes[k], side_ok)) != EVR_OK) {
                    free(nodes);
                    return st;
                }
            }
        }
    }
    free(nodes);
    for (i = 0; i < s->num_nodes; i++) {
        const evr_curve *c = &s->nodes[i].w_curve;
        any |= s->nodes[i].animated;
        if (c->num_keys <= 0) continue;
        if (c->times[0] < t0) t0 = c->times[0];
        if (c->times[c->num_keys - 1] > t1) t1 = c->times[c->num_keys - 1];
    }
    if (t0 <= t1) { /* the animation's range covers the weight curves too */
        s->anim_start = any ? fmin(s->anim_start, t0) : t0;
        s->anim_end = any ? fmax(s->anim_end, t1) : t1;
    }
    return EVR_OK;
}

evr_status evr_import_deform(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_status st;
    unsigned i;
    for (i = 0; i < ai->mNumMeshes; i++) {
        if (ai->mMeshes[i]->mNumBones && (st = import_skin(im, (int)i)) != EVR_OK) return st;
        if (ai->mMeshes[i]->mNumAnimMeshes && (st = import_morph(im, (int)i)) != EVR_OK) return st;
    }
    if ((st = node_weights(im)) != EVR_OK) return st;
    return weight_curves(im);
}
