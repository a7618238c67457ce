/* mesh_skin.c - see mesh_skin.h. Written whole in memory, then atomically (temporary + rename). */
#include "mesh_skin.h"

#include <stdlib.h>
#include <string.h>

#include "crowdbake/atomic_file.h"

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(p, v);
}

cb_status cli_write_skin_texture(const char *path, const cb_mesh *mesh, cb_error *err)
{
    uint64_t vertices = 0;
    for (uint32_t i = 0; i < mesh->part_count; ++i) vertices += mesh->parts[i].vertex_count;
    if (vertices == 0 || vertices > (1u << 24))
        return cb_fail(err, CB_ERR_INPUT, "%s: the skin texture holds 1 to 16777216 vertices (ids exact in a float); the mesh has %llu",
                       path, (unsigned long long)vertices);
    uint32_t width = vertices < CB_SKIN_MAX_WIDTH ? (uint32_t)vertices : CB_SKIN_MAX_WIDTH;
    uint32_t rows = (uint32_t)((vertices + width - 1) / width), height = 2 * rows;
    size_t size = CB_SKIN_HEADER_BYTES + (size_t)width * height * 16;
    unsigned char *bytes = calloc(1, size);
    if (!bytes) return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for %zu bytes", path, size);
    memcpy(bytes, CB_SKIN_MAGIC, 8);
    put_u32(bytes + 8, 1), put_u32(bytes + 12, (uint32_t)vertices), put_u32(bytes + 16, width), put_u32(bytes + 20, height);
    uint64_t v = 0;
    for (uint32_t i = 0; i < mesh->part_count; ++i)
        for (uint32_t k = 0; k < mesh->parts[i].vertex_count; ++k, ++v) {
            const cb_mesh_part *p = &mesh->parts[i];
            unsigned char *joints = bytes + CB_SKIN_HEADER_BYTES + ((v / width) * 2 * width + v % width) * 16;
            unsigned char *weights = joints + (size_t)width * 16;
            for (int c = 0; c < 4; ++c) {
                put_f32(joints + 4 * c, (float)p->joints[(size_t)k * 4 + c]);
                put_f32(weights + 4 * c, p->weights[(size_t)k * 4 + c]);
            }
        }
    cb_atomic_file f;
    cb_status st = cb_atomic_open(&f, path, err);
    if (!st && ((st = cb_atomic_write(&f, bytes, size, err)) || (st = cb_atomic_commit(&f, err)))) cb_atomic_abort(&f);
    free(bytes);
    return st;
}
