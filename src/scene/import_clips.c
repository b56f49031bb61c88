/* Which animation clips play. A file may hold one clip per object (Blender exports them so: they
 * animate disjoint nodes and belong together) or several clips of one character (walk, run,
 * idle: they animate the same nodes and only one makes sense at a time). Played together from
 * time 0, the second kind would mix into one motion where the first clip wins per curve.
 *
 * The default rule: take the clips in file order, each one that animates no node a taken clip
 * animates. A clip animates the nodes its transform channels name, and those its morph-weight
 * and mesh channels name (a node of that name, else every node that places a mesh of that
 * name). The caller may instead choose "all" or one clip by name or index
 * (evr_load_options.animation, documented in include/evray.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

int evr_import_clip_played(const importer *im, unsigned a)
{
    return !im->clip_played || (a < (unsigned)im->s->num_animations && im->clip_played[a]);
}

/* What a clip's targets are gathered in: the nodes of clip `stamp` (each once). */
typedef struct {
    int *mark; /* per node: the last clip that named it */
    int *nodes;
    int count;
    int stamp;
} node_set;

static void set_add(node_set *ns, int node)
{
    if (ns->mark[node] == ns->stamp) return;
    ns->mark[node] = ns->stamp;
    ns->nodes[ns->count++] = node;
}

/* Adds the nodes a morph-weight or mesh channel's name stands for; 0 when there is none. */
static int add_mesh_target(const importer *im, node_set *ns, const char *name)
{
    const struct aiScene *ai = im->ai;
    int node = evr_import_find_node(im, name), i, found = 0;
    unsigned k;
    if (node >= 0) {
        set_add(ns, node);
        return 1;
    }
    for (i = 0; i < im->s->num_nodes; i++) {
        const struct aiNode *an = im->ai_nodes[i];
        for (k = 0; k < an->mNumMeshes; k++) {
            unsigned m = an->mMeshes[k];
            if (m < ai->mNumMeshes && !strcmp(ai->mMeshes[m]->mName.data, name)) {
                set_add(ns, i);
                found = 1;
                break;
            }
        }
    }
    return found;
}

static void widen(evr_clip *c, int *any, double t)
{
    if (!*any || t < c->start) c->start = t;
    if (!*any || t > c->end) c->end = t;
    *any = 1;
}

/* Clip a's nodes into ns and its time range (keys of the channels that name something in the
 * scene, in seconds by the same rule as import_anim.c) into c. */
static void clip_targets(const importer *im, unsigned a, node_set *ns, evr_clip *c)
{
    const struct aiAnimation *an = im->ai->mAnimations[a];
    double tps = evr_import_ticks_per_second(an);
    unsigned ch, k;
    int any = 0;
    ns->count = 0;
    ns->stamp = (int)a;
    for (ch = 0; ch < an->mNumChannels; ch++) {
        const struct aiNodeAnim *na = an->mChannels[ch];
        int node = evr_import_find_node(im, na->mNodeName.data);
        if (node < 0) continue; /* names no node of the scene */
        set_add(ns, node);
        /* keys Assimp synthesized (quirk (e)) are not the clip's */
        if (evr_import_channel_interp(im, a, na->mNodeName.data, PATH_T) >= 0)
            for (k = 0; k < na->mNumPositionKeys; k++)
                widen(c, &any, na->mPositionKeys[k].mTime / tps);
        if (evr_import_channel_interp(im, a, na->mNodeName.data, PATH_R) >= 0)
            for (k = 0; k < na->mNumRotationKeys; k++)
                widen(c, &any, na->mRotationKeys[k].mTime / tps);
        if (evr_import_channel_interp(im, a, na->mNodeName.data, PATH_S) >= 0)
            for (k = 0; k < na->mNumScalingKeys; k++)
                widen(c, &any, na->mScalingKeys[k].mTime / tps);
    }
    for (ch = 0; ch < an->mNumMorphMeshChannels; ch++) {
        const struct aiMeshMorphAnim *ma = an->mMorphMeshChannels[ch];
        if (!add_mesh_target(im, ns, ma->mName.data)) continue;
        for (k = 0; k < ma->mNumKeys; k++) widen(c, &any, ma->mKeys[k].mTime / tps);
    }
    for (ch = 0; ch < an->mNumMeshChannels; ch++) {
        const struct aiMeshAnim *ma = an->mMeshChannels[ch];
        if (!add_mesh_target(im, ns, ma->mName.data)) continue;
        for (k = 0; k < ma->mNumKeys; k++) widen(c, &any, ma->mKeys[k].mTime / tps);
    }
    c->num_nodes = ns->count;
}

/* A clip as the user names it: 'name', or clip N when it has none. */
static void clip_label(char *buf, size_t cap, const evr_scene *s, int a)
{
    if (s->clips[a].name[0]) snprintf(buf, cap, "'%.60s'", s->clips[a].name);
    else snprintf(buf, cap, "clip %d", a);
}

/* Appends text to a line of cap bytes; 0 (leaving the line as it was) when it would not fit
 * with `reserve` bytes left over. */
static int append(char *line, size_t cap, size_t reserve, const char *text)
{
    size_t len = strlen(line), n = strlen(text);
    if (len + n + reserve >= cap) return 0;
    memcpy(line + len, text, n + 1);
    return 1;
}

/* The labels of the clips whose flag is set, comma-separated, into buf; "and N more" for those
 * that do not fit. */
static void list_labels(char *buf, size_t cap, const evr_scene *s, const unsigned char *flag)
{
    int a, listed = 0, left = 0;
    buf[0] = 0;
    for (a = 0; a < s->num_animations; a++) {
        char label[80], item[96];
        if (!flag[a]) continue;
        clip_label(label, sizeof label, s, a);
        snprintf(item, sizeof item, "%s%s", listed ? ", " : "", label);
        if (!left && append(buf, cap, 24, item)) listed++; /* room kept for "and N more" */
        else left++;
    }
    if (left) {
        char more[24];
        snprintf(more, sizeof more, " and %d more", left);
        append(buf, cap, 0, more);
    }
}

/* The notice naming the clips the default rule leaves out, and what they share nodes with
 * (skipped and owners: one scratch flag per clip each). */
static void make_notice(evr_scene *s, unsigned char *skipped, unsigned char *owners)
{
    int a, nskip = 0, nown = 0;
    char skip_list[256], owner_list[160];
    memset(skipped, 0, (size_t)s->num_animations);
    memset(owners, 0, (size_t)s->num_animations);
    for (a = 0; a < s->num_animations; a++) {
        if (s->clips[a].played) continue;
        skipped[a] = 1;
        nskip++;
        if (!owners[s->clips[a].conflict]) nown++;
        owners[s->clips[a].conflict] = 1;
    }
    if (!nskip) return;
    list_labels(skip_list, sizeof skip_list, s, skipped);
    list_labels(owner_list, sizeof owner_list, s, owners);
    snprintf(s->notice, sizeof s->notice,
             "animation clip%s not played: %s (%s nodes that %s %s); choose with --animation "
             "NAME|INDEX|all",
             nskip == 1 ? "" : "s", skip_list, nskip == 1 ? "it animates" : "they animate",
             owner_list, nown == 1 ? "animates" : "animate");
}

/* The clips as an error message lists them: "0 'walk', 1 'run'" (cut short with "..."). */
static void list_clips(char *buf, size_t cap, const evr_scene *s)
{
    int a;
    buf[0] = 0;
    for (a = 0; a < s->num_animations; a++) {
        char item[96];
        if (s->clips[a].name[0])
            snprintf(item, sizeof item, "%s%d '%.60s'", a ? ", " : "", a, s->clips[a].name);
        else snprintf(item, sizeof item, "%s%d (unnamed)", a ? ", " : "", a);
        if (!append(buf, cap, 4, item)) {
            append(buf, cap, 0, ", ...");
            return;
        }
    }
}

/* The clip `choice` names: a name first, then a 0-based index; -1 when none. */
static int find_clip(const importer *im, const char *choice)
{
    unsigned a;
    const char *p;
    unsigned long v = 0;
    for (a = 0; a < im->ai->mNumAnimations; a++)
        if (!strcmp(im->ai->mAnimations[a]->mName.data, choice)) return (int)a;
    for (p = choice; *p; p++) {
        if (*p < '0' || *p > '9' || p - choice > 9) return -1;
        v = v * 10 + (unsigned long)(*p - '0');
    }
    return v < im->ai->mNumAnimations ? (int)v : -1;
}

evr_status evr_import_clips(importer *im, const char *choice)
{
    evr_scene *s = im->s;
    int n = (int)im->ai->mNumAnimations, a, chosen = -1, i;
    node_set ns;
    int *owner = NULL;
    evr_status st = EVR_OK;

    s->num_animations = n;
    s->clip_choice = !choice || !choice[0]    ? EVR_CLIPS_DEFAULT
                     : !strcmp(choice, "all") ? EVR_CLIPS_ALL
                                              : EVR_CLIPS_ONE;
    if (s->clip_choice == EVR_CLIPS_ONE && n == 0)
        return evr_import_fail(im->err, EVR_ERR_ARG,
                               "no animation clip '%s' in '%s': it has no animation clips", choice,
                               s->source);
    if (n == 0) return EVR_OK;

    memset(&ns, 0, sizeof ns);
    s->clips = calloc((size_t)n, sizeof *s->clips);
    im->clip_played = calloc((size_t)n, 1);
    ns.mark = malloc((size_t)s->num_nodes * sizeof *ns.mark);
    ns.nodes = malloc((size_t)s->num_nodes * sizeof *ns.nodes);
    owner = malloc((size_t)s->num_nodes * sizeof *owner);
    if (!s->clips || !im->clip_played || !ns.mark || !ns.nodes || !owner) {
        st = evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading animations");
        goto done;
    }
    for (i = 0; i < s->num_nodes; i++) ns.mark[i] = owner[i] = -1;
    for (a = 0; a < n; a++)
        evr_import_copy_name(s->clips[a].name, sizeof s->clips[a].name,
                             im->ai->mAnimations[a]->mName.data);

    if (s->clip_choice == EVR_CLIPS_ONE && (chosen = find_clip(im, choice)) < 0) {
        char clips[320];
        list_clips(clips, sizeof clips, s);
        st = evr_import_fail(im->err, EVR_ERR_ARG,
                             "no animation clip '%s' in '%s' (its clips: %s; or all)", choice,
                             s->source, clips);
        goto done;
    }
    for (a = 0; a < n; a++) {
        evr_clip *c = &s->clips[a];
        clip_targets(im, (unsigned)a, &ns, c);
        c->conflict = -1;
        if (s->clip_choice == EVR_CLIPS_ALL) c->played = 1;
        else if (s->clip_choice == EVR_CLIPS_ONE) c->played = a == chosen;
        else {
            for (i = 0; i < ns.count; i++) /* played clips are disjoint: one owner per node */
                if (owner[ns.nodes[i]] >= 0 &&
                    (c->conflict < 0 || owner[ns.nodes[i]] < c->conflict))
                    c->conflict = owner[ns.nodes[i]];
            c->played = c->conflict < 0;
            if (c->played)
                for (i = 0; i < ns.count; i++) owner[ns.nodes[i]] = a;
        }
        im->clip_played[a] = (unsigned char)c->played;
    }
    if (s->clip_choice == EVR_CLIPS_DEFAULT) {
        unsigned char *flags = malloc((size_t)n * 2);
        if (!flags) {
            st = evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading animations");
            goto done;
        }
        make_notice(s, flags, flags + n);
        free(flags);
    }
done:
    free(ns.mark);
    free(ns.nodes);
    free(owner);
    return st;
}
