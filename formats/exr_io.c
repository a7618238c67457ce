/* exr_io.c - see exr_io.h. */
#include "crowdbake/exr.h"

#include <openexr.h>
#include <unistd.h>

#include "internal/atomic_file.h"
#include "internal/plumbing.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *const compressions[] = {"none", "rle", "zips", "zip", "piz"};

bool cb_exr_compression_parse(const char *text, int *out)
{
    for (int i = 0; i < 5; ++i)
        if (strcmp(text, compressions[i]) == 0) return *out = i, true;
    return false;
}

/* OpenEXR reports through a callback; keep the first message for our one-line error. */
static void remember_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *user = NULL;
    exr_get_user_data(ctxt, &user);
    char *buf = user;
    if (buf && !buf[0]) snprintf(buf, 256, "%s (%s)", msg ? msg : "", exr_get_default_error_message(code));
}

static int component_of(const char *channel)
{
    return channel[0] == 'R' ? 0 : channel[0] == 'G' ? 1 : channel[0] == 'B' ? 2 : 3;
}

static exr_result_t set_metadata(exr_context_t c, int part, const cb_palette *p, const cb_model *m, int32_t skin,
                                 uint64_t input_hash, float speed_reference)
{
    char key[96], hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)input_hash);
    exr_result_t rc = EXR_ERR_SUCCESS;
    rc |= exr_attr_set_string(c, part, "crowdbake.generator", "crowdbake " CROWDBAKE_VERSION);
    rc |= exr_attr_set_string(c, part, "crowdbake.layout", cb_layout_name(p->layout));
    rc |= exr_attr_set_string(c, part, "crowdbake.precision", cb_precision_name(p->precision));
    rc |= exr_attr_set_string(c, part, "crowdbake.inputHash", hash);
    rc |= exr_attr_set_int(c, part, "crowdbake.bones", (int32_t)p->bone_count);
    rc |= exr_attr_set_int(c, part, "crowdbake.texelsPerBone", (int32_t)p->texels_per_bone);
    rc |= exr_attr_set_int(c, part, "crowdbake.rows", (int32_t)p->rows);
    rc |= exr_attr_set_int(c, part, "crowdbake.rowsPerBlock", (int32_t)p->height);
    rc |= exr_attr_set_int(c, part, "crowdbake.blocks", (int32_t)p->blocks);
    rc |= exr_attr_set_int(c, part, "crowdbake.clips", (int32_t)p->clip_count);
    rc |= exr_attr_set_float(c, part, "crowdbake.fps", (float)p->fps);
    rc |= exr_attr_set_float(c, part, "crowdbake.speedReference", speed_reference);
    rc |= exr_attr_set_float(c, part, "crowdbake.maxError", (float)p->max_error);
    rc |= exr_attr_set_double(c, part, "crowdbake.modelHeight", p->model_height);
    rc |= exr_attr_set_float(c, part, "crowdbake.visibleError", (float)p->visible_error);
    rc |= exr_attr_set_int(c, part, "crowdbake.positionsRelative", p->positions_relative); /* see docs/pal-format.md */
    rc |= exr_attr_set_float_vector(c, part, "crowdbake.bindPositions", (int32_t)p->bone_count * 3, p->bind_positions);
    if (p->fitted) rc |= exr_attr_set_int(c, part, "crowdbake.fittedRows", 1); /* every clip's, as the .pal's flag bit 3 */
    if (p->positions_relative) /* what the positions are relative to (an EXR without it: the bind positions) */
        rc |= exr_attr_set_float_vector(c, part, "crowdbake.positionOffsets", (int32_t)p->bone_count * 3, p->position_offsets);
    const cb_skin *sk = &m->skins[skin];
    const char **names = malloc(sizeof(char *) * sk->joint_count);
    if (!names) return EXR_ERR_OUT_OF_MEMORY;
    for (uint32_t j = 0; j < sk->joint_count; ++j) names[j] = m->nodes[sk->joints[j]].name;
    rc |= exr_attr_set_string_vector(c, part, "crowdbake.boneNames", (int32_t)sk->joint_count, names);
    free(names);
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        const cb_palette_clip *cl = &p->clips[i];
        exr_attr_v3f_t v = {{{cl->root_velocity[0], cl->root_velocity[1], cl->root_velocity[2]}}};
        exr_attr_v3f_t lo = {{{cl->bounds_min[0], cl->bounds_min[1], cl->bounds_min[2]}}};
        exr_attr_v3f_t hi = {{{cl->bounds_max[0], cl->bounds_max[1], cl->bounds_max[2]}}};
#define KEY(field) (snprintf(key, sizeof key, "crowdbake.clip%u." field, i), key)
        rc |= exr_attr_set_string(c, part, KEY("name"), cl->name);
        rc |= exr_attr_set_int(c, part, KEY("firstRow"), (int32_t)cl->first_row);
        rc |= exr_attr_set_int(c, part, KEY("frames"), (int32_t)cl->frames);
        rc |= exr_attr_set_int(c, part, KEY("loops"), cl->loops);
        if (cl->fitted) rc |= exr_attr_set_int(c, part, KEY("fittedRows"), 1); /* as the .pal's clip flag bit 1 */
        if (cl->step) rc |= exr_attr_set_int(c, part, KEY("stepRows"), 1); /* held, not blended: clip flag bit 2 */
        rc |= exr_attr_set_float(c, part, KEY("fps"), (float)cl->fps);
        rc |= exr_attr_set_float(c, part, KEY("duration"), (float)cl->duration);
        rc |= exr_attr_set_double(c, part, KEY("start"), cl->start);
        rc |= exr_attr_set_v3f(c, part, KEY("rootVelocity"), &v);
        rc |= exr_attr_set_v3f(c, part, KEY("boundsMin"), &lo);
        rc |= exr_attr_set_v3f(c, part, KEY("boundsMax"), &hi);
#undef KEY
    }
    return rc;
}

/* Where each EXR channel's values come from: interleaved pixels in memory. */
typedef struct channel_source {
    const char *name;
    const uint8_t *base; /* pixel (0, 0) */
    int32_t pixel_stride, line_stride;
    int16_t bytes;       /* per value: 2 half, 4 float */
} channel_source;

static exr_result_t write_scanlines(exr_context_t c, int part, uint32_t height, const channel_source *src, int n)
{
    int32_t per_chunk = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(c, part, &per_chunk);
    exr_encode_pipeline_t enc;
    memset(&enc, 0, sizeof enc);
    bool started = false;
    for (int32_t y = 0; rc == EXR_ERR_SUCCESS && y < (int32_t)height; y += per_chunk) {
        exr_chunk_info_t cinfo;
        rc = exr_write_scanline_chunk_info(c, part, y, &cinfo);
        if (rc) break;
        rc = started ? exr_encoding_update(c, part, &cinfo, &enc) : exr_encoding_initialize(c, part, &cinfo, &enc);
        if (rc) break;
        for (int16_t k = 0; k < enc.channel_count; ++k) {
            exr_coding_channel_info_t *ch = &enc.channels[k];
            const channel_source *s = NULL;
            for (int i = 0; i < n && !s; ++i)
                if (strcmp(src[i].name, ch->channel_name) == 0) s = &src[i];
            if (!s) return EXR_ERR_INVALID_ARGUMENT;
            ch->encode_from_ptr = s->base + (size_t)y * s->line_stride;
            ch->user_pixel_stride = s->pixel_stride;
            ch->user_line_stride = s->line_stride;
            ch->user_bytes_per_element = s->bytes;
            ch->user_data_type = s->bytes == 4 ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF;
        }
        if (!started) rc = exr_encoding_choose_default_routines(c, part, &enc);
        started = true;
        if (!rc) rc = exr_encoding_run(c, part, &enc);
    }
    if (started) exr_encoding_destroy(c, &enc);
    return rc;
}

/* Opens `path` for writing (OpenEXR renames a temporary file over it on success), adds one
 * scanline part of width x height and the given channels. */
static exr_result_t start_image(const char *path, char *message, uint32_t width, uint32_t height, int compression,
                                const channel_source *src, int n, exr_context_t *c)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = remember_error;
    init.user_data = message;
    int part = 0;
    exr_result_t rc = exr_start_write(c, path, EXR_WRITE_FILE_DIRECTLY, &init); /* path: our temporary */
    if (!rc) rc = exr_add_part(*c, "palette", EXR_STORAGE_SCANLINE, &part);
    if (!rc) rc = exr_initialize_required_attr_simple(*c, part, (int32_t)width, (int32_t)height, (exr_compression_t)compression);
    for (int i = 0; i < n && !rc; ++i)
        rc = exr_add_channel(*c, part, src[i].name, src[i].bytes == 4 ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF,
                             EXR_PERCEPTUALLY_LINEAR, 1, 1);
    return rc;
}

/* OpenEXR writes the atomic file's temporary; it replaces `path` only when all went well. */
static cb_status finish_image(const char *path, const char *message, exr_result_t rc, exr_context_t c, cb_atomic_file *af,
                              cb_error *err)
{
    exr_result_t fin = c ? exr_finish(&c) : EXR_ERR_SUCCESS;
    if (rc || fin) {
        cb_atomic_abort(af);
        return cb_fail(err, CB_ERR_IO, "%s: OpenEXR could not write the file: %s", path,
                       message[0] ? message : exr_get_default_error_message(rc ? rc : fin));
    }
    return cb_atomic_commit(af, err);
}

static cb_status open_temp(const char *path, cb_atomic_file *af, cb_error *err)
{
    if (cb_atomic_open(af, path, err)) return err->status;
    close(af->fd);
    af->fd = -1;
    return CB_OK;
}

cb_status cb_exr_write(const char *path, const cb_palette *p, const cb_model *m, int32_t skin, int compression,
                       uint64_t input_hash, float speed_reference, cb_error *err)
{
    if (p->precision == CB_PRECISION_U16)
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_PRECISION,
                               "%s: EXR stores half or float texels; bake half or float precision, or write a .pal for u16", path);
    if (cb_palette_timed_clip(p))
        return cb_fail(err, CB_ERR_INPUT, "%s: clip %s has timed rows, and timed rows need a .pal (EXR has no place for "
                       "their map): write a .pal, or bake it at a fixed --fps", path, cb_palette_timed_clip(p)->name);
    if (p->width > INT32_MAX || p->height > INT32_MAX) return cb_fail(err, CB_ERR_INPUT, "%s: palette too large", path);
    int16_t bytes = p->precision == CB_PRECISION_FLOAT ? 4 : 2;
    int32_t stride = 4 * bytes, line = (int32_t)(p->width * 4 * bytes);
    const uint8_t *t = p->texels;
    channel_source src[4] = {{"A", t + 3 * bytes, stride, line, bytes}, {"B", t + 2 * bytes, stride, line, bytes},
                             {"G", t + bytes, stride, line, bytes}, {"R", t, stride, line, bytes}};
    char message[256] = "";
    exr_context_t c = NULL;
    cb_atomic_file af;
    if (open_temp(path, &af, err)) return err->status;
    exr_result_t rc = start_image(af.tmp_path, message, p->width, p->height, compression, src, 4, &c);
    if (!rc) rc = set_metadata(c, 0, p, m, skin, input_hash, speed_reference);
    if (!rc) rc = exr_write_header(c);
    if (!rc) rc = write_scanlines(c, 0, p->height, src, 4);
    return finish_image(path, message, rc, c, &af, err);
}

cb_status cb_exr_write_vat(const char *path, const cb_vat *vat, int compression, cb_error *err)
{
    int32_t line = (int32_t)(vat->geometry.width * 8);
    const uint8_t *pp = (const uint8_t *)vat->positions, *nn = (const uint8_t *)vat->normals;
    channel_source src[8] = {{"normal.A", nn + 6, 8, line, 2},   {"normal.B", nn + 4, 8, line, 2},
                             {"normal.G", nn + 2, 8, line, 2},   {"normal.R", nn, 8, line, 2},
                             {"position.A", pp + 6, 8, line, 2}, {"position.B", pp + 4, 8, line, 2},
                             {"position.G", pp + 2, 8, line, 2}, {"position.R", pp, 8, line, 2}};
    char message[256] = "";
    exr_context_t c = NULL;
    cb_atomic_file af;
    if (open_temp(path, &af, err)) return err->status;
    exr_result_t rc = start_image(af.tmp_path, message, vat->geometry.width, vat->geometry.height, compression, src, 8, &c);
    rc |= rc ? 0 : exr_attr_set_string(c, 0, "crowdbake.generator", "crowdbake " CROWDBAKE_VERSION " vat");
    rc |= rc ? 0 : exr_attr_set_int(c, 0, "crowdbake.vertices", (int32_t)vat->vertices);
    rc |= rc ? 0 : exr_attr_set_int(c, 0, "crowdbake.frames", (int32_t)vat->frames);
    rc |= rc ? 0 : exr_attr_set_int(c, 0, "crowdbake.rowsPerFrame", (int32_t)vat->rows_per_frame);
    rc |= rc ? 0 : exr_attr_set_int(c, 0, "crowdbake.frameWidth", (int32_t)vat->frame_width);
    rc |= rc ? 0 : exr_attr_set_int(c, 0, "crowdbake.blocks", (int32_t)vat->geometry.blocks);
    rc |= rc ? 0 : exr_attr_set_float(c, 0, "crowdbake.maxError", (float)vat->max_error);
    if (!rc) rc = exr_write_header(c);
    if (!rc) rc = write_scanlines(c, 0, vat->geometry.height, src, 8);
    return finish_image(path, message, rc, c, &af, err);
}

/* ---- reading ---- */

static exr_result_t read_scanlines(exr_context_t c, int part, cb_exr_image *img)
{
    int32_t per_chunk = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(c, part, &per_chunk);
    uint32_t tb = cb_precision_texel_bytes(img->precision), comp_bytes = tb / 4;
    exr_decode_pipeline_t dec;
    memset(&dec, 0, sizeof dec);
    bool started = false;
    for (int32_t y = 0; rc == EXR_ERR_SUCCESS && y < (int32_t)img->height; y += per_chunk) {
        exr_chunk_info_t cinfo;
        rc = exr_read_scanline_chunk_info(c, part, y, &cinfo);
        if (rc) break;
        rc = started ? exr_decoding_update(c, part, &cinfo, &dec) : exr_decoding_initialize(c, part, &cinfo, &dec);
        if (rc) break;
        for (int16_t k = 0; k < dec.channel_count; ++k) {
            exr_coding_channel_info_t *ch = &dec.channels[k];
            ch->decode_to_ptr = (uint8_t *)img->texels + ((size_t)(cinfo.start_y) * img->width) * tb +
                                (size_t)component_of(ch->channel_name) * comp_bytes;
            ch->user_pixel_stride = (int32_t)tb;
            ch->user_line_stride = (int32_t)(img->width * tb);
            ch->user_bytes_per_element = (int16_t)comp_bytes;
            ch->user_data_type = img->precision == CB_PRECISION_FLOAT ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF;
        }
        if (!started) rc = exr_decoding_choose_default_routines(c, part, &dec);
        started = true;
        if (!rc) rc = exr_decoding_run(c, part, &dec);
    }
    if (started) exr_decoding_destroy(c, &dec);
    return rc;
}

/* A palette: channels A, B, G, R of one type, unsampled, a data window from 0,0 of sane size.
 * Checked before anything is allocated: the header can claim any size. */
static bool palette_shaped(const char *path, const exr_attr_box2i_t *dw, const exr_attr_chlist_t *chans, cb_error *err)
{
    bool ok = chans->num_channels == 4 && dw->min.x == 0 && dw->min.y == 0;
    for (int i = 0; ok && i < 4; ++i) {
        const exr_attr_chlist_entry_t *e = &chans->entries[i];
        ok = e->name.length == 1 && e->name.str[0] == "ABGR"[i] && e->pixel_type == chans->entries[0].pixel_type &&
             (e->pixel_type == EXR_PIXEL_HALF || e->pixel_type == EXR_PIXEL_FLOAT) && e->x_sampling == 1 && e->y_sampling == 1;
    }
    if (!ok) {
        cb_fail(err, CB_ERR_INPUT, "%s: not a crowdbake palette (expects half or float channels A, B, G, R from 0,0)", path);
        return false;
    }
    struct stat st;
    uint64_t w = (uint64_t)dw->max.x + 1, h = (uint64_t)dw->max.y + 1, file = stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
    uint64_t bytes = w * h * (chans->entries[0].pixel_type == EXR_PIXEL_FLOAT ? 16 : 8);
    if (dw->max.x < 0 || dw->max.y < 0 || w > 65536 || h > 65536 || bytes > (1ull << 30) || bytes > 4096 * file) {
        cb_fail(err, CB_ERR_INPUT, "%s: claims %llux%llu texels, more than the file can hold or a palette can be", path,
                (unsigned long long)w, (unsigned long long)h);
        return false;
    }
    return true;
}

/* The clip table and bones of a palette EXR, from its crowdbake.* attributes, as a view that
 * skins like the .pal: everything it points to is allocated here. */
static bool read_palette_attributes(exr_const_context_t c, const char *path, const cb_exr_image *img, cb_exr_palette *out,
                                    cb_error *err)
{
    cb_palette *p = &out->palette;
    int32_t tpb = 0, n = 0, len = 0;
    const float *bind = NULL;
    exr_attr_get_int(c, 0, "crowdbake.texelsPerBone", &tpb);
    exr_attr_get_float_vector(c, 0, "crowdbake.bindPositions", &n, &bind);
    /* Every count is the file's: products in 64 bits (a fuzzer found 3 * bones overflowing), and
     * no more clips than the header has attributes (each has its own), before they are allocated. */
    int32_t attributes = 0;
    exr_get_attribute_count(c, 0, &attributes);
    if (!cb_layout_parse(img->layout, &p->layout) || tpb != (int32_t)cb_layout_texels_per_bone(p->layout) ||
        img->bones <= 0 || n != 3 * (int64_t)img->bones || img->clips < 0 || img->clips > attributes ||
        img->rows_per_block <= 0 || img->blocks <= 0 ||
        (int64_t)img->blocks * tpb * img->bones != (int64_t)img->width || img->rows_per_block != (int32_t)img->height ||
        img->rows <= 0 || img->rows > (int64_t)img->blocks * img->rows_per_block)
        return cb_fail(err, CB_ERR_INPUT, "%s: an EXR without a consistent crowdbake palette header (bake it with "
                       "'crowdbake bake MODEL -o OUT.exr')", path), false;
    p->precision = img->precision;
    p->bone_count = (uint32_t)img->bones;
    p->texels_per_bone = (uint32_t)tpb;
    p->row_texels = p->bone_count * p->texels_per_bone;
    p->rows = (uint32_t)img->rows;
    p->width = img->width, p->height = img->height, p->blocks = (uint32_t)img->blocks;
    float fps = 0, max_error = 0, visible_error = 0;
    int32_t relative = 0, fitted = 0;
    exr_attr_get_float(c, 0, "crowdbake.fps", &fps);
    exr_attr_get_float(c, 0, "crowdbake.maxError", &max_error);
    exr_attr_get_float(c, 0, "crowdbake.visibleError", &visible_error);
    exr_attr_get_double(c, 0, "crowdbake.modelHeight", &p->model_height);
    exr_attr_get_int(c, 0, "crowdbake.positionsRelative", &relative); /* qpos/half: positions less the bind's */
    p->fps = fps, p->max_error = max_error, p->visible_error = visible_error;
    p->positions_relative = relative != 0;
    exr_attr_get_int(c, 0, "crowdbake.fittedRows", &fitted);
    p->fitted = fitted != 0;
    p->texels = img->texels;
    p->texel_bytes = img->texel_bytes;
    int32_t n_offsets = 0;
    const float *offsets = NULL;
    exr_attr_get_float_vector(c, 0, "crowdbake.positionOffsets", &n_offsets, &offsets);
    if (!offsets || n_offsets != n) offsets = bind; /* written before the offsets: relative to the bind positions */
    p->bind_positions = malloc(sizeof(float) * (size_t)n);
    p->position_offsets = malloc(sizeof(float) * (size_t)n);
    p->clips = calloc(img->clips ? (size_t)img->clips : 1, sizeof *p->clips);
    out->names = calloc((size_t)img->clips + 1, 256);
    if (!p->bind_positions || !p->position_offsets || !p->clips || !out->names)
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory"), false;
    memcpy(p->bind_positions, bind, sizeof(float) * (size_t)n);
    memcpy(p->position_offsets, offsets, sizeof(float) * (size_t)n);
    p->clip_count = (uint32_t)img->clips;
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        cb_palette_clip *cl = &p->clips[i];
        char key[96], *name = out->names + 256 * (size_t)i;
        const char *text = NULL;
        int32_t first = -1, frames = 0, loops = 0, clip_fitted = p->fitted, step = 0; /* fitted: before per clip, all */
        float cfps = 0, duration = 0;
        exr_attr_v3f_t v = {{{0, 0, 0}}}, lo = v, hi = v;
#define KEY(field) (snprintf(key, sizeof key, "crowdbake.clip%u." field, i), key)
        if (exr_attr_get_string(c, 0, KEY("name"), &len, &text) == EXR_ERR_SUCCESS && text)
            snprintf(name, 256, "%.*s", len < 255 ? (int)len : 255, text);
        exr_attr_get_int(c, 0, KEY("firstRow"), &first);
        exr_attr_get_int(c, 0, KEY("frames"), &frames);
        exr_attr_get_int(c, 0, KEY("loops"), &loops);
        exr_attr_get_int(c, 0, KEY("fittedRows"), &clip_fitted);
        exr_attr_get_int(c, 0, KEY("stepRows"), &step);
        exr_attr_get_float(c, 0, KEY("fps"), &cfps);
        exr_attr_get_float(c, 0, KEY("duration"), &duration);
        exr_attr_get_double(c, 0, KEY("start"), &cl->start); /* absent before 0.1.x: clips started at 0 */
        exr_attr_get_v3f(c, 0, KEY("rootVelocity"), &v);
        exr_attr_get_v3f(c, 0, KEY("boundsMin"), &lo);
        exr_attr_get_v3f(c, 0, KEY("boundsMax"), &hi);
#undef KEY
        if (first < 0 || frames <= 0 || (int64_t)first + frames > img->rows || !name[0])
            return cb_fail(err, CB_ERR_INPUT, "%s: clip %u of its crowdbake header is missing or lies outside its %d rows",
                           path, i, img->rows), false;
        cl->name = name;
        cl->first_row = (uint32_t)first, cl->frames = (uint32_t)frames, cl->loops = loops != 0, cl->fitted = clip_fitted != 0;
        cl->step = step != 0;
        cl->fps = cfps, cl->duration = duration;
        memcpy(cl->root_velocity, v.arr, sizeof cl->root_velocity);
        memcpy(cl->bounds_min, lo.arr, sizeof cl->bounds_min);
        memcpy(cl->bounds_max, hi.arr, sizeof cl->bounds_max);
    }
    return true;
}

/* Reads the texels and the main attributes; with `palette`, the whole palette view too. */
static cb_status exr_read(const char *path, cb_exr_image *img, cb_exr_palette *palette, cb_error *err)
{
    memset(img, 0, sizeof *img);
    char message[256] = "";
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = remember_error;
    init.user_data = message;
    exr_context_t c = NULL;
    exr_result_t rc = exr_start_read(&c, path, &init);
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *chans = NULL;
    if (!rc) rc = exr_get_data_window(c, 0, &dw);
    if (!rc) rc = exr_get_channels(c, 0, &chans);
    if (!rc && !palette_shaped(path, &dw, chans, err)) {
        exr_finish(&c);
        return CB_ERR_INPUT;
    }
    if (!rc) {
        img->width = (uint32_t)(dw.max.x + 1);
        img->height = (uint32_t)(dw.max.y + 1);
        img->precision = chans->entries[0].pixel_type == EXR_PIXEL_FLOAT ? CB_PRECISION_FLOAT : CB_PRECISION_HALF;
        img->texel_bytes = (size_t)img->width * img->height * cb_precision_texel_bytes(img->precision);
        img->texels = malloc(img->texel_bytes ? img->texel_bytes : 1);
        if (!img->texels) rc = EXR_ERR_OUT_OF_MEMORY;
    }
    if (!rc) rc = read_scanlines(c, 0, img);
    bool consistent = true;
    if (!rc) {
        const char *layout = NULL;
        int32_t len = 0;
        if (exr_attr_get_string(c, 0, "crowdbake.layout", &len, &layout) == EXR_ERR_SUCCESS && layout)
            snprintf(img->layout, sizeof img->layout, "%.*s", (int)len, layout);
        exr_attr_get_int(c, 0, "crowdbake.bones", &img->bones);
        exr_attr_get_int(c, 0, "crowdbake.rows", &img->rows);
        exr_attr_get_int(c, 0, "crowdbake.blocks", &img->blocks);
        exr_attr_get_int(c, 0, "crowdbake.rowsPerBlock", &img->rows_per_block);
        exr_attr_get_int(c, 0, "crowdbake.clips", &img->clips);
        exr_attr_get_float(c, 0, "crowdbake.maxError", &img->max_error);
        exr_attr_get_float(c, 0, "crowdbake.visibleError", &img->visible_error);
        const char *hash = NULL;
        if (exr_attr_get_string(c, 0, "crowdbake.inputHash", &len, &hash) == EXR_ERR_SUCCESS && hash && len == 16) {
            char hex[17];
            memcpy(hex, hash, 16);
            hex[16] = '\0';
            img->input_hash = strtoull(hex, NULL, 16);
        }
        if (palette) consistent = read_palette_attributes(c, path, img, palette, err);
    }
    if (c) exr_finish(&c);
    if (rc || !consistent) {
        cb_exr_image_free(img);
        if (!consistent) return err->status;
        return cb_fail(err, CB_ERR_INPUT, "%s: OpenEXR cannot read it: %s", path,
                       message[0] ? message : exr_get_default_error_message(rc));
    }
    return CB_OK;
}

cb_status cb_exr_read(const char *path, cb_exr_image *img, cb_error *err) { return exr_read(path, img, NULL, err); }

cb_status cb_exr_read_palette(const char *path, cb_exr_palette *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    cb_exr_image img;
    if (exr_read(path, &img, out, err)) {
        out->palette.texels = NULL; /* freed with the image */
        cb_exr_palette_free(out);
        return err->status;
    }
    return CB_OK;
}

void cb_exr_palette_free(cb_exr_palette *p)
{
    cb_palette_free(&p->palette);
    free(p->names);
    p->names = NULL;
}

void cb_exr_image_free(cb_exr_image *img)
{
    free(img->texels);
    img->texels = NULL;
}
