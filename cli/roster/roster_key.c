/* roster_key.c - a type's content key: everything that shapes its palette (the rig, its bind
 * pose, the planned clips' keys and the settings). Types with equal keys share one palette. */
#include <string.h>

#include "internal/bake_words.h"
#include "crowdbake_pal.h" /* XXH64 */
#include "roster_files.h"

static void hash_str(cbpal_xxh64_state *h, const char *s) { cbpal_xxh64_update(h, s, strlen(s) + 1); }

uint64_t roster_content_key(const cb_model *m, int32_t skin, const cb_clip_plan *plan, uint32_t n, const cb_bake_settings *b)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    hash_str(&h, "crowdbake " CROWDBAKE_VERSION);
    double settings[8] = {b->fps, b->layout + 10.0 * b->layout_set, b->precision + 10.0 * b->precision_set,
                          b->max_texture_size, b->root_motion, b->formats, b->zstd, b->exr_compression};
    cbpal_xxh64_update(&h, settings, sizeof settings);
    if (b->fit_rows) hash_str(&h, "fit_rows"); /* (only then: other palettes stay up to date) */
    if (b->measure_all) hash_str(&h, "measure_all"); /* (likewise: the header's errors may differ) */
    if (b->plant_feet) hash_str(&h, "plant_feet");   /* (likewise: the legs' rows differ) */
    if (b->row_travel_off) hash_str(&h, "row_travel_off"); /* (likewise: the travel table may go) */
    if (b->timed_rows != CB_TIMED_ROWS_AUTO) hash_str(&h, cb_timed_rows_name(b->timed_rows)); /* (likewise) */
    if (cb_bake_settings_bone_space(b, CB_FORMAT_PAL) == CB_BONE_SPACE_LOCAL) hash_str(&h, "bone-space=local"); /* (likewise) */
    if (b->allow_over_budget) hash_str(&h, "allow_over_budget"); /* a palette written over budget is not one that met it */
    /* A budget the command line gave (the catalog's own is in the canonical entry): a palette
     * checked against it is not one baked unchecked, nor one checked against another. */
    if (b->max_error_given && b->from.max_error == CB_FROM_COMMAND_LINE) {
        hash_str(&h, "max_error from the command line");
        cbpal_xxh64_update(&h, &b->max_error_mm, sizeof b->max_error_mm);
    }
    for (uint32_t i = 0; i < m->node_count; ++i) {
        const cb_node *node = &m->nodes[i];
        hash_str(&h, node->name);
        cbpal_xxh64_update(&h, &node->parent, sizeof node->parent);
        cbpal_xxh64_update(&h, node->translation, sizeof node->translation);
        cbpal_xxh64_update(&h, node->rotation, sizeof node->rotation);
        cbpal_xxh64_update(&h, node->scale, sizeof node->scale);
        if (node->has_matrix) cbpal_xxh64_update(&h, node->matrix, sizeof node->matrix);
    }
    const cb_skin *sk = &m->skins[skin];
    cbpal_xxh64_update(&h, sk->joints, sk->joint_count * sizeof(int32_t));
    cbpal_xxh64_update(&h, sk->inverse_bind, sk->joint_count * 16 * sizeof(double));
    for (uint32_t i = 0; i < n; ++i) {
        hash_str(&h, plan[i].name);
        cbpal_xxh64_update(&h, &plan[i].loop, sizeof plan[i].loop);
        cbpal_xxh64_update(&h, &plan[i].fps, sizeof plan[i].fps);
        if (plan[i].fit) hash_str(&h, "fit"); /* its rows fitted (error-bounded rates choose it per clip) */
        const cb_animation *a = &m->animations[plan[i].animation];
        for (uint32_t c = 0; c < a->channel_count; ++c) {
            const cb_channel *ch = &a->channels[c];
            int per_key = (ch->path == CB_PATH_ROTATION ? 4 : 3) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
            int32_t head[4] = {ch->node, (int32_t)ch->path, (int32_t)ch->interp, (int32_t)ch->key_count};
            cbpal_xxh64_update(&h, head, sizeof head);
            cbpal_xxh64_update(&h, ch->times, ch->key_count * sizeof(float));
            cbpal_xxh64_update(&h, ch->values, (size_t)ch->key_count * per_key * sizeof(float));
        }
    }
    return cbpal_xxh64_digest(&h);
}
