/* outputs.c - the table of output formats (crowdbake/outputs.h): a row per format, with its
 * writer and its reader. A new format is a row here and its writer in formats/. */
#include "outputs.h"

#include <string.h>

#include "crowdbake_pal.h"
#include "crowdbake/babylon.h"
#include "crowdbake/exr.h"
#include "crowdbake/ktx2.h"
#include "internal/plumbing.h"

/* Root motion taken out of some rows (in place, or loops in place): the files say so. */
static bool in_place(const cb_bake_job *job) { return job->settings.root_motion != CB_ROOT_MOTION_KEEP; }

static cb_status write_pal(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping,
                           const cb_bake_output *out, cb_error *err)
{
    cb_pal_write_options po = {job->settings.zstd, 0, out->input_hash, (float)job->speed_reference, in_place(job)};
    if (cb_pal_mapping_holds(mapping, p)) return cb_pal_write_mapped(mapping, p, &po, err);
    return cb_pal_write(out->path, p, job->model, job->skin, &po, err);
}

static cb_status write_exr(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping,
                           const cb_bake_output *out, cb_error *err)
{
    (void)mapping;
    return cb_exr_write(out->path, p, job->model, job->skin, job->settings.exr_compression, out->input_hash,
                        (float)job->speed_reference, err);
}

static cb_status write_ktx2(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping,
                            const cb_bake_output *out, cb_error *err)
{
    (void)mapping;
    /* --zstd: the level supercompressed as `toktx --zcmp` does, at the .pal payload's level */
    return cb_ktx2_write_zstd(out->path, p, job->model, job->skin, out->input_hash, (float)job->speed_reference,
                              in_place(job), job->settings.zstd ? 9 : 0, err);
}

static cb_status write_babylon(const cb_bake_job *job, const cb_palette *p, cb_pal_mapping *mapping,
                               const cb_bake_output *out, cb_error *err)
{
    (void)mapping;
    cb_babylon_write_options bo = {(float)job->speed_reference, in_place(job), out->input_hash, job->babylon_states,
                                   job->babylon_state_count};
    return cb_babylon_write(out->path, p, job->model, job->skin, &bo, err);
}

/* Verified (memory speed): a file torn by a power loss fails, so it is baked again, not trusted. */
static cb_status facts_pal(const char *path, cb_output_facts *out, cb_error *err)
{
    cbpal_file f;
    char msg[256];
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg) != 0)
        return cb_fail(err, CB_ERR_IO, "%s: %s", path, msg);
    const cbpal_header *h = &f.header;
    *out = (cb_output_facts){h->input_hash, h->rows, h->width, h->height, h->blocks, (cb_layout)h->layout,
                             (cb_precision)h->precision, h->max_error, h->visible_error, h->payload_raw_size};
    cbpal_close(&f);
    return CB_OK;
}

static cb_status facts_exr(const char *path, cb_output_facts *out, cb_error *err)
{
    cb_exr_image img;
    if (cb_exr_read(path, &img, err)) return err->status;
    cb_layout layout = CB_LAYOUT_MAT4;
    cb_layout_parse(img.layout, &layout);
    *out = (cb_output_facts){img.input_hash, (uint32_t)img.rows, img.width, img.height, (uint32_t)img.blocks, layout,
                             img.precision, img.max_error, img.visible_error, img.texel_bytes};
    cb_exr_image_free(&img);
    return CB_OK;
}

static cb_status facts_ktx2(const char *path, cb_output_facts *out, cb_error *err)
{
    cb_ktx2_palette k;
    if (cb_ktx2_read_palette(path, &k, err)) return err->status;
    const cb_palette *p = &k.palette;
    *out = (cb_output_facts){k.input_hash, p->rows, p->width, p->height, p->blocks, p->layout, p->precision,
                             (float)p->max_error, (float)p->visible_error, p->texel_bytes};
    cb_ktx2_palette_free(&k);
    return CB_OK;
}

/* A .bvat.json's rows are Babylon's (a loop's closing row added): the caller compares them. */
static cb_status facts_babylon(const char *path, cb_output_facts *out, cb_error *err)
{
    cb_babylon_facts b;
    if (cb_babylon_read_facts(path, &b, err)) return err->status;
    *out = (cb_output_facts){.input_hash = b.input_hash, .rows = b.height, .width = b.width, .height = b.height,
                             .layout = CB_LAYOUT_MAT4, .precision = CB_PRECISION_FLOAT};
    return CB_OK;
}

#define ALL_LAYOUTS ((1u << CB_LAYOUT_MAT4) | (1u << CB_LAYOUT_AFFINE) | (1u << CB_LAYOUT_QPOS))
#define FLOATS ((1u << CB_PRECISION_FLOAT) | (1u << CB_PRECISION_HALF))

/* The order is the order a bake writes them in, and each one's bit its place: it is the bytes'
 * order too (the first format's options choose the rates). */
static const bake_output_row rows[] = {
    {{CB_FORMAT_PAL, "pal", ".pal", "crowdbake's palette: every runtime reads it (docs/pal-format.md)", "palette",
      ALL_LAYOUTS, FLOATS | (1u << CB_PRECISION_U16), true, true, true},
     write_pal, facts_pal},
    {{CB_FORMAT_EXR, "exr", ".exr", "OpenEXR image of the palette, half or float", "palette_exr", ALL_LAYOUTS, FLOATS,
      false, true, true},
     write_exr, facts_exr},
    {{CB_FORMAT_KTX2, "ktx2", ".ktx2", "KTX2 texture of the palette (RGBA16F/RGBA32F), with its tables", "palette_ktx2",
      ALL_LAYOUTS, FLOATS, true, true, true},
     write_ktx2, facts_ktx2},
    /* Babylon.js's baked vertex animation texture is Float32 4x4 matrices; beside another format in a catalog,
     * whose palette the manifest describes. */
    {{CB_FORMAT_BABYLON, "babylon", ".bvat.json", "Babylon.js baked vertex animation data (float mat4)",
      "palette_babylon", 1u << CB_LAYOUT_MAT4, 1u << CB_PRECISION_FLOAT, false, true, false},
     write_babylon, facts_babylon},
};

#define ROW_COUNT (sizeof rows / sizeof rows[0])
_Static_assert(ROW_COUNT <= CB_OUTPUT_MAX, "CB_OUTPUT_MAX holds every format");

uint32_t cb_output_format_count(void) { return (uint32_t)ROW_COUNT; }

const cb_output_format *cb_output_format_at(uint32_t i) { return i < ROW_COUNT ? &rows[i].format : NULL; }

const bake_output_row *bake_output_row_of(unsigned format)
{
    for (size_t i = 0; i < ROW_COUNT; ++i)
        if (rows[i].format.format == format) return &rows[i];
    return NULL;
}

const cb_output_format *cb_output_format_of(unsigned format)
{
    const bake_output_row *r = bake_output_row_of(format);
    return r ? &r->format : NULL;
}

const cb_output_format *cb_output_format_named(const char *name, size_t length)
{
    for (size_t i = 0; i < ROW_COUNT; ++i)
        if (strlen(rows[i].format.name) == length && strncmp(name, rows[i].format.name, length) == 0)
            return &rows[i].format;
    return NULL;
}

const cb_output_format *cb_output_format_for_path(const char *path)
{
    size_t n = strlen(path);
    for (size_t i = 0; i < ROW_COUNT; ++i) {
        size_t e = strlen(rows[i].format.extension);
        if (n > e && strcmp(path + n - e, rows[i].format.extension) == 0 && path[n - e - 1] != '/')
            return &rows[i].format;
    }
    return NULL;
}

cb_status cb_output_read_facts(unsigned format, const char *path, cb_output_facts *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    const bake_output_row *r = bake_output_row_of(format);
    if (!r) return cb_fail(err, CB_ERR_INTERNAL, "%s: no output format has the bit %u", path, format);
    return r->read_facts(path, out, err);
}
