/* roster_fresh.c - a type's outputs by the table of formats (outputs.h): their paths, and
 * whether the files on disk are this bake's (the roster's up-to-date check): each format's file
 * read back by its reader, its recorded input hash and rows compared. */
#include "roster_files.h"
#include "internal/bake_words.h"

const char *roster_output_path(const cb_roster_type *t, unsigned format)
{
    for (uint32_t i = 0; i < cb_output_format_count(); ++i)
        if (cb_output_format_at(i)->format == format && (t->animal->bake.formats & format)) return t->paths[i];
    return "";
}

const char *roster_palette_path(const cb_roster_type *t)
{
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if ((t->animal->bake.formats & f->format) && f->holds_palette) return t->paths[i];
    }
    return "";
}

bool roster_local_rows(const cb_roster_type *t)
{
    const cb_bake_settings *b = &t->animal->bake; /* the bake's own decision; a rig qpos cannot hold bakes global */
    return (b->formats & CB_FORMAT_PAL) && cb_bake_settings_bone_space(b, CB_FORMAT_PAL) == CB_BONE_SPACE_LOCAL &&
           t->layout == CB_LAYOUT_QPOS;
}

/* The rows the file of format f holds for this bake: the palette's, or Babylon's own. */
static uint32_t rows_expected(const cb_roster_type *t, const cb_output_format *f)
{
    return f->holds_palette ? t->rows : roster_babylon_from(t, t->clip_count);
}

/* True when every output exists and records this key; fills the geometry from the first that
 * holds the palette. */
bool roster_outputs_up_to_date(cb_roster_type *t, unsigned formats)
{
    bool filled = false;
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if (!(formats & f->format)) continue;
        cb_output_facts facts;
        cb_error e = {0};
        if (cb_output_read_facts(f->format, t->paths[i], &facts, &e)) return false;
        if (facts.input_hash != t->input_hash || facts.rows != rows_expected(t, f)) return false;
        if (filled || !f->holds_palette) continue;
        t->width = facts.width, t->height = facts.height, t->blocks = facts.blocks;
        t->layout = facts.layout, t->precision = facts.precision;
        t->max_error = facts.max_error, t->visible_error = facts.visible_error;
        t->palette_bytes = facts.texel_bytes;
        filled = true;
    }
    return true;
}
