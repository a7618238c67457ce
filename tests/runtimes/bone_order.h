/* bone_order.h - a local palette (.pal version 6) renumbered so that every parent comes after its
 * children, which none of the shared models does: the runtimes' tests hold "do not assume parent <
 * child" (the spec) with it. Header-only, like testutil.h. */
#ifndef CB_BONE_ORDER_H
#define CB_BONE_ORDER_H

#include "crowdbake/pal_write.h"
#include "crowdbake/palette.h"

static inline void reverse_floats(float *v, uint32_t n, size_t each)
{
    for (uint32_t j = 0; j < n / 2; ++j)
        for (size_t k = 0; k < each; ++k) {
            float t = v[j * each + k];
            v[j * each + k] = v[(n - 1 - j) * each + k], v[(n - 1 - j) * each + k] = t;
        }
}

/* A local palette and its mesh with the bone order reversed (bone j becomes n - 1 - j): every parent
 * then comes after its children, which no shared model does. Texels, bind positions, parents,
 * ranges and the mesh's joints renumbered; what is skinned is unchanged. */
static inline void reverse_bones(cb_palette *p, cb_primitive *prim)
{
    uint32_t n = p->bone_count, x, y;
    size_t bone_bytes = cb_layout_texels_per_bone(p->layout) * cb_precision_texel_bytes(p->precision);
    unsigned char *t = malloc(p->texel_bytes), *from = p->texels;
    memcpy(t, from, p->texel_bytes);
    for (uint32_t r = 0; r < p->rows; ++r)
        for (uint32_t j = 0; j < n; ++j) {
            cb_palette_texel_xy(p, r, j, &x, &y);
            size_t at = ((size_t)y * p->width + x) * cb_precision_texel_bytes(p->precision);
            cb_palette_texel_xy(p, r, n - 1 - j, &x, &y);
            memcpy(t + ((size_t)y * p->width + x) * cb_precision_texel_bytes(p->precision), from + at, bone_bytes);
        }
    memcpy(p->texels, t, p->texel_bytes);
    free(t);
    reverse_floats(p->bind_positions, n, 3), reverse_floats(p->position_offsets, n, 3), reverse_floats(p->bone_ranges, n, 8);
    int32_t *parents = malloc(n * sizeof *parents);
    for (uint32_t j = 0; j < n; ++j) parents[n - 1 - j] = p->parents[j] < 0 ? -1 : (int32_t)n - 1 - p->parents[j];
    memcpy(p->parents, parents, n * sizeof *parents);
    free(parents);
    for (size_t i = 0; i < (size_t)prim->vertex_count * 4; ++i) prim->joints[i] = (uint16_t)(n - 1 - prim->joints[i]);
    bool after = false;
    for (uint32_t j = 0; j < n; ++j) after |= p->parents[j] > (int32_t)j;
    assert_true(after);
}

/* The skin's joints reversed as reverse_bones reverses the palette, so cb_pal_write writes the
 * reversed bone table (names and parents follow). */
static inline void reverse_skin(cb_skin *skin)
{
    for (uint32_t j = 0, n = skin->joint_count; j < n / 2; ++j) {
        int32_t t = skin->joints[j];
        skin->joints[j] = skin->joints[n - 1 - j], skin->joints[n - 1 - j] = t;
    }
}

/* Bakes the quadruped sample's local rows (qpos u16) and writes them as a .pal, its bones reversed
 * (every parent after its children: runtimes/bone_order.h) when `reversed`. */
static inline void write_local_quadruped(const char *path, bool reversed)
{
    char model_path[1024];
    snprintf(model_path, sizeof model_path, "%s/quadruped.glb", samples_dir());
    cb_model *model = load_or_fail(model_path);
    cb_error err = {0};
    cb_sampler *sampler = cb_sampler_create(model, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = CB_LAYOUT_QPOS, o.precision = CB_PRECISION_U16, o.bone_space = CB_BONE_SPACE_LOCAL;
    cb_palette p;
    assert_int_equal(cb_palette_bake(sampler, &o, NULL, 0, &p, &err), CB_OK);
    if (reversed) reverse_bones(&p, &model->primitives[0]), reverse_skin(&model->skins[0]);
    cb_pal_write_options w = {0};
    if (cb_pal_write(path, &p, model, 0, &w, &err)) fail_msg("%s", err.message);
    cb_sampler_free(sampler);
    cb_palette_free(&p);
    cb_model_free(model);
}

#endif
