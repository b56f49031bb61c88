#include "io/h5_instances.h"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define NODE_CHARS 256
#define MESH_CHARS 64

typedef struct {
    uint32_t id;
    char node[NODE_CHARS];
    char mesh[MESH_CHARS];
} instance_row;

herr_t evr_h5_write_instances(hid_t loc, const char *const *node, const char *const *mesh, int n)
{
    hsize_t len = (hsize_t)(n > 0 ? n : 0);
    instance_row *rows = calloc(len ? len : 1, sizeof *rows);
    hid_t sn = H5Tcopy(H5T_C_S1), sm = H5Tcopy(H5T_C_S1),
          type = H5Tcreate(H5T_COMPOUND, sizeof(instance_row)), space = -1, ds = -1,
          dcpl = H5Pcreate(H5P_DATASET_CREATE);
    herr_t r = -1;
    /* no time stamps: the same run gives the same bytes */
    if (rows && sn >= 0 && sm >= 0 && type >= 0 && dcpl >= 0 &&
        H5Pset_obj_track_times(dcpl, 0) >= 0 && H5Tset_size(sn, NODE_CHARS) >= 0 &&
        H5Tset_size(sm, MESH_CHARS) >= 0 &&
        H5Tinsert(type, "id", offsetof(instance_row, id), H5T_STD_U32LE) >= 0 &&
        H5Tinsert(type, "node", offsetof(instance_row, node), sn) >= 0 &&
        H5Tinsert(type, "mesh", offsetof(instance_row, mesh), sm) >= 0 &&
        (space = H5Screate_simple(1, &len, NULL)) >= 0 &&
        (ds = H5Dcreate2(loc, "instances", type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT)) >= 0) {
        for (hsize_t i = 0; i < len; i++) {
            rows[i].id = (uint32_t)i + 1;
            snprintf(rows[i].node, NODE_CHARS, "%s", node[i]);
            snprintf(rows[i].mesh, MESH_CHARS, "%s", mesh[i]);
        }
        r = len ? H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) : 0;
    }
    if (ds >= 0) H5Dclose(ds);
    if (space >= 0) H5Sclose(space);
    if (dcpl >= 0) H5Pclose(dcpl);
    if (type >= 0) H5Tclose(type);
    if (sn >= 0) H5Tclose(sn);
    if (sm >= 0) H5Tclose(sm);
    free(rows);
    return r;
}
