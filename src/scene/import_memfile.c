/* The aiFileIO every import goes through. It serves Assimp the scene file (from memory: a
 * patched copy, quirk (j) in import.c, or a scene given in memory; else from disk) under the
 * file's own name, and every other file Assimp asks for (the buffers a .gltf names, an OBJ's
 * material library, ...) from disk when evr_import_file_check allows it: inside the scene's
 * folder unless external files are allowed, and never a FIFO or a device. A refused file is one
 * Assimp cannot open. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/cfileio.h>

#include "io/file_read.h"
#include "scene/import_internal.h"

typedef struct {
    struct aiFileIO io; /* first: Assimp's callbacks get this pointer */
    const char *path;
    const unsigned char *bytes; /* NULL: the file on disk */
    size_t n;
    const char *dir; /* the scene's folder (NULL: none, a scene in memory) */
    int allow_external;
} memfile_io;

typedef struct {
    struct aiFile f; /* first, as above */
    FILE *fp;        /* NULL: the bytes in memory */
    const unsigned char *bytes;
    size_t n, pos;
} memfile;

static size_t mf_read(struct aiFile *af, char *buf, size_t size, size_t count)
{
    memfile *m = (memfile *)af;
    size_t items;
    if (m->fp) return fread(buf, size, count, m->fp);
    if (size == 0) return 0;
    items = (m->n - m->pos) / size;
    if (items > count) items = count;
    memcpy(buf, m->bytes + m->pos, items * size);
    m->pos += items * size;
    return items;
}

static size_t mf_write(struct aiFile *af, const char *buf, size_t size, size_t count)
{
    return 0; /* read only */
}

static size_t mf_tell(struct aiFile *af)
{
    memfile *m = (memfile *)af;
    long p;
    if (!m->fp) return m->pos;
    p = ftell(m->fp);
    return p < 0 ? 0 : (size_t)p;
}

static size_t mf_size(struct aiFile *af)
{
    memfile *m = (memfile *)af;
    long here, end;
    if (!m->fp) return m->n;
    here = ftell(m->fp);
    if (here < 0 || fseek(m->fp, 0, SEEK_END) != 0) return 0;
    end = ftell(m->fp);
    if (fseek(m->fp, here, SEEK_SET) != 0 || end < 0) return 0;
    return (size_t)end;
}

static enum aiReturn mf_seek(struct aiFile *af, size_t off, enum aiOrigin origin)
{
    memfile *m = (memfile *)af;
    size_t base;
    if (m->fp) {
        int whence = origin == aiOrigin_SET   ? SEEK_SET
                     : origin == aiOrigin_CUR ? SEEK_CUR
                                              : SEEK_END;
        return fseek(m->fp, (long)off, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
    }
    base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? m->pos : m->n;
    if (off > m->n - base) return aiReturn_FAILURE;
    m->pos = base + off;
    return aiReturn_SUCCESS;
}

static void mf_flush(struct aiFile *af) {}

static struct aiFile *mf_open(struct aiFileIO *io, const char *path, const char *mode)
{
    memfile_io *mio = (memfile_io *)io;
    memfile *m;
    if (strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+')) return NULL;
    m = calloc(1, sizeof *m);
    if (!m) return NULL;
    if (!strcmp(path, mio->path) && mio->bytes) {
        m->bytes = mio->bytes;
        m->n = mio->n;
    } else {
        const char *why;
        if ((strcmp(path, mio->path) &&
             evr_import_file_check(mio->dir, path, mio->allow_external, "file", NULL) != EVR_OK) ||
            !(m->fp = evr_fopen_regular(path, &why))) {
            free(m);
            return NULL;
        }
    }
    m->f.ReadProc = mf_read;
    m->f.WriteProc = mf_write;
    m->f.TellProc = mf_tell;
    m->f.FileSizeProc = mf_size;
    m->f.SeekProc = mf_seek;
    m->f.FlushProc = mf_flush;
    return &m->f;
}

static void mf_close(struct aiFileIO *io, struct aiFile *af)
{
    memfile *m = (memfile *)af;
    if (!m) return;
    if (m->fp) fclose(m->fp);
    free(m);
}

struct aiFileIO *evr_memfile_io_new(const char *path, const unsigned char *bytes, size_t n,
                                    const char *dir, int allow_external)
{
    memfile_io *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->io.OpenProc = mf_open;
    m->io.CloseProc = mf_close;
    m->path = path;
    m->bytes = bytes;
    m->n = n;
    m->dir = dir;
    m->allow_external = allow_external;
    return &m->io;
}

void evr_memfile_io_free(struct aiFileIO *io) { free(io); }
