/* What the two units of the glTF check share (import_gltf_validate.c: the container and the
 * binary data; import_gltf_validate_refs.c: the elements that use them). Every helper returns 0
 * when the value is good and -1 after filling the error with one line ("glTF: ..."). */
#ifndef EVR_SCENE_IMPORT_GLTF_VALIDATE_H
#define EVR_SCENE_IMPORT_GLTF_VALIDATE_H

#include <stdarg.h>

#include "scene/import_internal.h"

typedef struct {
    const gltf_source *src;
    const evr_jdoc *d;
    evr_error *err;
    evr_status err_status; /* set when the error is not EVR_ERR_FORMAT */
    int root;
    gltf_data data; /* accessors read through import_gltf_data.c */
    int glb, has_bin;
    size_t bin_len;
    int n_buffers, n_views, n_acc, n_meshes, n_nodes, n_scenes, n_skins, n_cameras, n_materials,
        n_textures, n_images, n_samplers, n_anims;
    double *buf_len, *view_len, *view_stride; /* from the JSON, checked */
    int *acc_count, *acc_comps, *acc_ctype;   /* per accessor, checked */
    unsigned char *acc_checked;               /* per accessor: its values were found finite */
    int *parent;                              /* per node: its parent, -1 for a root */
} gv;

int evr_gv_fail(gv *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* The array member key of obj: its value, -1 when absent, -2 (after an error) when it is not an
 * array. */
int evr_gv_array(gv *c, int obj, const char *key, const char *what);
/* An index member: *out in [0, n), or -1 when absent and not required. `of` names what it
 * indexes in the message ("node", "accessor"). */
int evr_gv_index(gv *c, int obj, const char *key, int n, int required, const char *what,
                 const char *of, int *out);
int evr_gv_index_value(gv *c, int v, int n, const char *what, const char *of, int *out);
/* An integer member in [lo, hi]; def when absent (NAN: required). */
int evr_gv_integer(gv *c, int obj, const char *key, double lo, double hi, double def,
                   const char *what, double *out);
/* An array member of `want` finite numbers (want 0: any number of them) into out (may be NULL):
 * 1 when absent. */
int evr_gv_numbers(gv *c, int obj, const char *key, int want, double *out, const char *what);
/* A finite number member, def when absent. */
int evr_gv_number(gv *c, int obj, const char *key, double def, const char *what, double *out);
/* 1 when a "data:" URI has the form data:TYPE/SUBTYPE;base64, in less than 128 bytes (all
 * Assimp reads safely). */
int evr_gv_data_uri(const char *uri);
/* The bytes base64 text s[0 .. n) decodes to (json: as it stands in the JSON text, "\/" for
 * '/'), or (size_t)-1 when it is not standard padded base64. */
size_t evr_gv_base64(const char *s, size_t n, int json);
/* Accessor a's values (evr_gltf_accessor_read). */
int evr_gv_read(gv *c, int a, double **vals, int *count, int *nc);
/* Every value of accessor a finite (read once per accessor). */
int evr_gv_finite(gv *c, int a, const char *what);
/* The meshes, nodes, scenes, skins, animations, cameras, lights, textures and images
 * (import_gltf_validate_refs.c), after the buffers, views and accessors. */
int evr_gv_refs(gv *c);

#endif
