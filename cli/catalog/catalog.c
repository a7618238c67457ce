/* catalog.c - see catalog.h: bake settings given for one run, over a whole catalog. */
#include "catalog/catalog.h"

static void override_settings(cb_bake_settings *b, const cb_bake_settings *v, unsigned fields)
{
    if (fields & CB_BAKE_FPS) b->fps = v->fps, b->fps_auto = v->fps_auto, b->from.fps = CB_FROM_COMMAND_LINE;
    if (fields & CB_BAKE_MAX_ERROR)
        b->max_error_mm = v->max_error_mm, b->max_error_given = true, b->from.max_error = CB_FROM_COMMAND_LINE;
    if (fields & CB_BAKE_MAX_FPS) b->max_fps = v->max_fps, b->from.max_fps = CB_FROM_COMMAND_LINE;
    if (fields & CB_BAKE_ALLOW_OVER_BUDGET) b->allow_over_budget = v->allow_over_budget;
    if (fields & CB_BAKE_LAYOUT) b->layout = v->layout, b->layout_set = true;
    if (fields & CB_BAKE_PRECISION) b->precision = v->precision, b->precision_set = true;
    if (fields & CB_BAKE_FORMATS) b->formats = v->formats;
    if (fields & CB_BAKE_MAX_TEXTURE_SIZE) b->max_texture_size = v->max_texture_size;
    if (fields & CB_BAKE_ROOT_MOTION) b->root_motion = v->root_motion, b->from.root_motion = CB_FROM_COMMAND_LINE;
    if (fields & CB_BAKE_FIT_ROWS) b->fit_rows = v->fit_rows, b->from.fit_rows = CB_FROM_COMMAND_LINE;
    if (fields & CB_BAKE_MEASURE_ALL) b->measure_all = v->measure_all;
    if (fields & CB_BAKE_PLANT_FEET) b->plant_feet = v->plant_feet;
    if (fields & CB_BAKE_ROW_TRAVEL) b->row_travel_off = v->row_travel_off;
    if (fields & CB_BAKE_BONE_SPACE) b->bone_space = v->bone_space, b->bone_space_set = true;
    if (fields & CB_BAKE_TIMED_ROWS) b->timed_rows = v->timed_rows;
    if (fields & CB_BAKE_ZSTD) b->zstd = v->zstd;
    if (fields & CB_BAKE_EXR_COMPRESSION) b->exr_compression = v->exr_compression;
    if (fields & CB_BAKE_OUT_DIR) b->out_dir = v->out_dir;
}

bool cb_catalog_formats_valid(unsigned formats)
{
    bool palette = false;
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if (!(formats & f->format)) continue;
        if (!f->in_catalogs) return false;
        palette |= f->holds_palette;
        formats &= ~f->format;
    }
    return palette && !formats;
}

cb_status cb_catalog_override_bake(cb_catalog *cat, const cb_bake_settings *values, unsigned fields, cb_error *err)
{
    override_settings(&cat->defaults, values, fields);
    for (uint32_t i = 0; i < cat->animal_count; ++i) {
        cb_bake_settings *b = &cat->animals[i].bake;
        override_settings(b, values, fields);
        if (!cb_bake_settings_writable(b))
            return cb_fail(err, CB_ERR_SETTINGS, "%s: [animal.%s] would write u16 texels to EXR, which holds half or float "
                           "only; choose the precision half or float, or the format pal", cat->path, cat->animals[i].name);
    }
    return CB_OK;
}
