/* report.c - see report.h and docs/budget.md for every formula. */
#include "report_parts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal/json.h"

void cb_human_bytes(uint64_t b, char *buf, size_t size)
{
    const char *units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double v = (double)b;
    int u = 0;
    while (v >= 1024 && u < 4) v /= 1024, ++u;
    if (u == 0) snprintf(buf, size, "%llu B", (unsigned long long)b);
    else snprintf(buf, size, v < 10 ? "%.2f %s" : v < 100 ? "%.1f %s" : "%.0f %s", v, units[u]);
}


static cb_status resolve_budget(const cb_catalog *cat, cb_report *r, cb_error *err)
{
    const cb_budget *b = &cat->budget;
    r->max_texture_size = 16384;
    r->max_bones = 256;
    if (!b->set) return CB_OK;
    const cb_target_profile *p = cb_find_profile(b->target);
    if (!p && !b->vram_bytes) {
        char list[512] = "";
        for (uint32_t i = 0; i < cb_profile_count; ++i)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s\"%s\"", i ? ", " : "", cb_profiles[i].name);
        if (!b->pos.line) /* --target */
            return cb_fail(err, CB_ERR_SETTINGS, "--target \"%s\" is not a built-in profile (%s)", b->target, list);
        return cb_fail(err, CB_ERR_INPUT, "%s:%u:%u: [budget] target \"%s\" is not a built-in profile (%s); give its vram",
                       cat->path, b->pos.line, b->pos.column, b->target, list);
    }
    r->has_budget = true;
    snprintf(r->target, sizeof r->target, "%s", p ? p->name : b->target ? b->target : "custom");
    r->profile_source = p ? p->source : "defined in the catalog";
    r->vram_bytes = b->vram_bytes ? b->vram_bytes : p->vram_bytes;
    r->crowd_share = b->crowd_share > 0 ? b->crowd_share : 1;
    r->budget_bytes = (uint64_t)llround((double)r->vram_bytes * r->crowd_share);
    r->max_texture_size = b->max_texture_size ? b->max_texture_size : p ? p->max_texture_size : 16384;
    r->max_bones = b->max_bones ? b->max_bones : 256;
    return CB_OK;
}

static void fill_type(const cb_roster *roster, uint32_t i, const cb_report *r, cb_report_type *t)
{
    const cb_roster_type *rt = &roster->types[i];
    const cb_roster_type *owner = &roster->types[rt->owner];
    t->name = rt->animal->name;
    t->shares = rt->owner != i ? owner->animal->name : NULL;
    t->bones = rt->bones;
    t->frames = rt->rows;
    t->vertices = rt->vertices;
    t->indices = rt->indices;
    t->layout = owner->layout;
    t->precision = owner->precision;
    t->local_rows = roster_local_rows(owner);
    t->width = owner->width, t->height = owner->height, t->blocks = owner->blocks;
    t->palette_bytes = owner->palette_bytes;
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) {
            cb_texture_geometry g;
            t->encoding_bytes[l][p] = cb_palette_texture_bytes(t->bones, t->frames, (cb_layout)l, (cb_precision)p,
                                                               r->max_texture_size, &g);
        }
    t->vat_fits = cb_vat_geometry(t->vertices, t->frames, r->max_texture_size, &t->vat_geometry);
    for (int e = 0; e < CB_VAT_ENCODINGS; ++e)
        t->vat_bytes[e] = cb_vat_bytes(t->vertices, t->frames, &cb_vat_encodings[e], &t->vat_geometry);
    t->mesh_bytes = rt->mesh_bytes;
    t->palette_error = owner->max_error;
    t->palette_visible_error = owner->visible_error;
    t->vat_error = rt->vat_error;
    t->model_height = rt->model_height;
    t->palette_over_limit = t->width > r->max_texture_size || t->height > r->max_texture_size;
    t->bones_over_limit = t->bones > r->max_bones;
    report_fill_gaits(rt, t);
    t->bake_warnings = &rt->warnings;
}

cb_status cb_report_build(const cb_catalog *cat, const cb_roster *roster, cb_report *r, cb_error *err)
{
    memset(r, 0, sizeof *r);
    if (resolve_budget(cat, r, err)) return err->status;
    r->types = calloc(roster->type_count ? roster->type_count : 1, sizeof *r->types);
    if (!r->types) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; i < roster->type_count; ++i) {
        if (roster->types[i].outcome == CB_TYPE_FAILED) {
            r->failed_types++;
            continue;
        }
        cb_report_type *t = &r->types[r->type_count++];
        fill_type(roster, i, r, t);
        t->roster_index = i;
        if (!t->shares) r->palettes_total += t->palette_bytes; /* a shared palette is one texture */
        for (uint32_t k = 0; k + 1 < r->type_count && !t->mesh_of; ++k) /* one mesh per model, however many types use it */
            if (strcmp(roster->types[r->types[k].roster_index].animal->model, roster->types[i].animal->model) == 0)
                t->mesh_of = r->types[k].mesh_of ? r->types[k].mesh_of : r->types[k].name;
        if (!t->mesh_of) r->meshes_total += t->mesh_bytes;
        for (int e = 0; e < CB_VAT_ENCODINGS; ++e) r->vat_total[e] += t->vat_bytes[e];
        r->warnings += t->palette_over_limit + t->bones_over_limit + !t->vat_fits + report_gait_warnings(t);
    }
    r->total = r->palettes_total + r->meshes_total;
    r->over_budget = r->has_budget && r->total > r->budget_bytes;
    cb_report_fill_herds(r);
    return CB_OK;
}

void cb_report_add_runtime(const cb_roster *roster, cb_report *r, FILE *progress)
{
    /* Types whose models hold the same bytes measure the same meshes: once (without memory: each) */
    report_mesh_memo memo = {0, calloc(r->type_count ? r->type_count : 1, sizeof *memo.items)};
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_roster_type *t = &roster->types[r->types[i].roster_index];
        cb_error inner = {0}; /* the bake succeeded: a model that cannot be measured again only loses that section */
        cb_report_runtime_measure(t, &roster->types[t->owner], memo.items ? &memo : NULL, &r->types[i].runtime, &inner);
        if (progress) fprintf(progress, "crowdbake: [%u/%u] %s: runtime meshes measured\n", i + 1, r->type_count, r->types[i].name);
    }
    free(memo.items);
}

void cb_report_free(cb_report *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i) cb_report_runtime_free(&r->types[i].runtime), free(r->types[i].gaits);
    free(r->types);
    memset(r, 0, sizeof *r);
}

/* ---- shared pieces of the renderings ---- */

/* The limits a type breaks, "; "-separated, or "". */
const char *report_limit_warnings(const cb_report_type *t, char *buf, size_t size)
{
    buf[0] = '\0';
    if (t->palette_over_limit) snprintf(buf + strlen(buf), size - strlen(buf), "PALETTE OVER TEXTURE LIMIT; ");
    if (!t->vat_fits) snprintf(buf + strlen(buf), size - strlen(buf), "VAT over texture limit; ");
    if (t->bones_over_limit) snprintf(buf + strlen(buf), size - strlen(buf), "BONES OVER SHADER LIMIT; ");
    size_t n = strlen(buf);
    if (n >= 2) buf[n - 2] = '\0';
    return buf;
}

const char *report_encoding(const cb_report_type *t, char *buf, size_t size)
{
    snprintf(buf, size, "%s/%s%s", cb_layout_name(t->layout), cb_precision_name(t->precision), t->local_rows ? " local" : "");
    return buf;
}

bool report_encoding_holds(const cb_report_type *t, int layout, int precision)
{
    return !t->local_rows || cb_holds_local_rows((cb_layout)layout, (cb_precision)precision);
}

bool report_has_local_rows(const cb_report *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i)
        if (r->types[i].local_rows) return true;
    return false;
}

const char *report_notes(const cb_report_type *t, char *buf, size_t size)
{
    char limits[192];
    report_limit_warnings(t, limits, sizeof limits);
    snprintf(buf, size, "%s%s%s%s", t->shares ? "shares " : "", t->shares ? t->shares : "", t->shares ? "'s palette" : "",
             t->shares && limits[0] ? "; " : "");
    snprintf(buf + strlen(buf), size - strlen(buf), "%s", limits);
    if (t->mesh_of)
        snprintf(buf + strlen(buf), size - strlen(buf), "%smesh counted with %s (same model)", buf[0] ? "; " : "", t->mesh_of);
    return buf;
}

double report_ratio(uint64_t a, uint64_t b) { return b ? (double)a / b : 0; }

void report_budget_line(FILE *f, const cb_report *r, const char *bold, const char *line_end)
{
    char total[32], budget[32], vram[32], vat[32];
    cb_human_bytes(r->total, total, sizeof total);
    cb_human_bytes(r->vat_total[0] + r->meshes_total, vat, sizeof vat);
    if (r->failed_types) { /* a roster missing types passes no budget */
        fprintf(f, "%sRoster: INCOMPLETE, %u animal type%s failed to bake; the %s counted leave %s out, so the budget "
                "is not checked.%s\n", bold, r->failed_types, r->failed_types == 1 ? "" : "s", total,
                r->failed_types == 1 ? "it" : "them", bold);
        return;
    }
    if (!r->has_budget) {
        fprintf(f, "Roster: %s of palettes and meshes (as VAT: %s); no budget to check (%s).\n", total, vat,
                r->single_model ? "give --target NAME" : "add a [budget] to the catalog, or give --target NAME");
        return;
    }
    cb_human_bytes(r->budget_bytes, budget, sizeof budget);
    cb_human_bytes(r->vram_bytes, vram, sizeof vram);
    char verdict[64] = "fits";
    if (r->over_budget) {
        char over[32];
        cb_human_bytes(r->total - r->budget_bytes, over, sizeof over);
        snprintf(verdict, sizeof verdict, "OVER BUDGET by %s", over);
    }
    /* The verdict alone on its line (a CI greps it); the VAT comparison on the next, in neutral words. */
    fprintf(f, "%sRoster: %s = %.2f%% of the %s crowd budget (%s: crowd_share %g of %s): %s.%s%s", bold, total,
            100.0 * r->total / r->budget_bytes, r->target, budget, r->crowd_share, vram, verdict, bold, line_end);
    fprintf(f, "As VAT (RGBA16F + RGBA8), the same frames and meshes would take %s = %.2f%% of that budget.\n", vat,
            100.0 * (r->vat_total[0] + r->meshes_total) / r->budget_bytes);
}

/* ---- terminal ---- */

void cb_report_text(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], note[256];
    fprintf(f, "%-14s %6s %7s %9s %-14s %10s %10s %7s %10s %9s %9s %9s  %s\n", "type", "bones", "rows", "vertices",
            "palette", "bytes", "VAT 16F+8", "VAT/pal", "mesh", "enc mm/m", "seen mm/m", "VAT mm/m", "notes");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char enc[32];
        report_encoding(t, enc, sizeof enc);
        cb_human_bytes(t->palette_bytes, a, sizeof a);
        cb_human_bytes(t->vat_bytes[0], b, sizeof b);
        cb_human_bytes(t->mesh_bytes, c, sizeof c);
        fprintf(f, "%-14s %6u %7u %9llu %-14s %10s %10s %6.1fx %10s %9.3f %9.3f %9.3f  %s\n", t->name, t->bones, t->frames,
                (unsigned long long)t->vertices, enc, a, b, report_ratio(t->vat_bytes[0], t->palette_bytes), c,
                cb_mm_per_m(t->palette_error, t->model_height), cb_mm_per_m(t->palette_visible_error, t->model_height),
                cb_mm_per_m(t->vat_error, t->model_height), report_notes(t, note, sizeof note));
    }
    fprintf(f, "\nEvery encoding (texture bytes at the %u-texel limit):\n%-14s", r->max_texture_size, "type");
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) {
            char h[24];
            snprintf(h, sizeof h, "%s/%s", cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)p));
            fprintf(f, " %12s", h);
        }
    fputc('\n', f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        fprintf(f, "%-14s", r->types[i].name);
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                cb_human_bytes(r->types[i].encoding_bytes[l][p], a, sizeof a);
                fprintf(f, " %12s", !report_encoding_holds(&r->types[i], l, p) ? "-"
                                    : r->types[i].encoding_bytes[l][p] ? a : "too big");
            }
        fputc('\n', f);
    }
    if (report_has_local_rows(r))
        fputs("-: local rows (the default bone space) are held in qpos with u16 or float only; bone_space = \"global\" "
              "for the others\n", f);
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    fprintf(f, "\nPalettes %s (shared palettes once) + meshes %s. VAT instead of palettes:", a, b);
    for (int e = 0; e < CB_VAT_ENCODINGS; ++e) {
        cb_human_bytes(r->vat_total[e], c, sizeof c);
        fprintf(f, "%s %s %s (%.1fx)", e ? "," : "", cb_vat_encodings[e].name, c, report_ratio(r->vat_total[e], r->palettes_total));
    }
    fputs(".\n", f);
    cb_report_runtime_text(f, r);
    report_gaits_text(f, r);
    report_herds_text(f, r);
    report_budget_line(f, r, "", "\n");
    if (r->warnings) fprintf(f, "%u warning%s (see notes and foot-sync).\n", r->warnings, r->warnings == 1 ? "" : "s");
}

/* ---- Markdown ---- */

void cb_report_markdown(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], note[256];
    fputs("## crowdbake roster report\n\n", f);
    report_budget_line(f, r, "**", "  \n"); /* Markdown's line break: the VAT line under the verdict */
    fputs("\n| type | bones | rows | vertices | palette | bytes | VAT RGBA16F+RGBA8 | VAT / palette | mesh | palette encoding "
          "error mm/m | palette visible error mm/m | VAT error mm/m | notes |\n|---|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|---|\n",
          f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char enc[32];
        cb_human_bytes(t->palette_bytes, a, sizeof a);
        cb_human_bytes(t->vat_bytes[0], b, sizeof b);
        cb_human_bytes(t->mesh_bytes, c, sizeof c);
        fprintf(f, "| %s | %u | %u | %llu | %s | %s | %s | %.1f× | %s | %.3f | %.3f | %.3f | %s |\n", t->name, t->bones,
                t->frames, (unsigned long long)t->vertices, report_encoding(t, enc, sizeof enc), a, b,
                report_ratio(t->vat_bytes[0], t->palette_bytes), c, cb_mm_per_m(t->palette_error, t->model_height),
                cb_mm_per_m(t->palette_visible_error, t->model_height), cb_mm_per_m(t->vat_error, t->model_height),
                report_notes(t, note, sizeof note));
    }
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    cb_human_bytes(r->vat_total[0], c, sizeof c);
    fprintf(f, "| **total** | | | | | **%s** | **%s** | %.1f× | %s | | | | |\n", a, c, report_ratio(r->vat_total[0], r->palettes_total), b);
    cb_report_runtime_markdown(f, r);
    report_gaits_markdown(f, r);
}

/* ---- JSON (docs/report.schema.json) ---- */

void cb_report_json(FILE *f, const cb_report *r)
{
    cb_json j;
    cb_json_init(&j, f);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "schema", "crowdbake-report/1");
    if (r->has_budget) {
        cb_json_object(&j, "budget");
        cb_json_string(&j, "target", r->target);
        cb_json_string(&j, "source", r->profile_source);
        cb_json_int(&j, "vram_bytes", (long long)r->vram_bytes);
        cb_json_number(&j, "crowd_share", r->crowd_share);
        cb_json_int(&j, "budget_bytes", (long long)r->budget_bytes);
        report_vertex_rate_json(&j, r);
        cb_json_end(&j);
    }
    cb_json_int(&j, "max_texture_size", r->max_texture_size);
    cb_json_int(&j, "max_bones", r->max_bones);
    cb_json_array(&j, "types");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", t->name);
        if (t->shares) cb_json_string(&j, "shares_palette_of", t->shares);
        cb_json_int(&j, "bones", t->bones);
        cb_json_int(&j, "rows", t->frames);
        cb_json_int(&j, "vertices", (long long)t->vertices);
        cb_json_int(&j, "indices", (long long)t->indices);
        cb_json_object(&j, "palette");
        cb_json_string(&j, "layout", cb_layout_name(t->layout));
        cb_json_string(&j, "precision", cb_precision_name(t->precision));
        cb_json_string(&j, "bone_space", t->local_rows ? "local" : "global"); /* of the .pal */
        cb_json_int(&j, "width", t->width);
        cb_json_int(&j, "height", t->height);
        cb_json_int(&j, "blocks", t->blocks);
        cb_json_int(&j, "bytes", (long long)t->palette_bytes);
        cb_json_number(&j, "max_error", t->palette_error);
        cb_json_number(&j, "visible_error", t->palette_visible_error);
        cb_json_end(&j);
        cb_json_object(&j, "encodings");
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                char key[32];
                snprintf(key, sizeof key, "%s/%s", cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)p));
                cb_json_int(&j, key, (long long)t->encoding_bytes[l][p]);
            }
        cb_json_end(&j);
        cb_json_object(&j, "vat");
        for (int e = 0; e < CB_VAT_ENCODINGS; ++e) cb_json_int(&j, cb_vat_encodings[e].name, (long long)t->vat_bytes[e]);
        cb_json_bool(&j, "fits_texture_limit", t->vat_fits);
        cb_json_int(&j, "width", t->vat_geometry.width);
        cb_json_int(&j, "height", t->vat_geometry.height);
        cb_json_number(&j, "max_error", t->vat_error);
        cb_json_number(&j, "ratio_to_palette", report_ratio(t->vat_bytes[0], t->palette_bytes));
        cb_json_end(&j);
        cb_json_int(&j, "mesh_bytes", (long long)t->mesh_bytes);
        if (t->mesh_of) cb_json_string(&j, "mesh_counted_with", t->mesh_of);
        cb_json_number(&j, "model_height", t->model_height);
        cb_json_bool(&j, "palette_over_texture_limit", t->palette_over_limit);
        cb_json_bool(&j, "bones_over_limit", t->bones_over_limit);
        cb_report_runtime_json(&j, &t->runtime);
        report_gaits_json(&j, t);
        report_herds_json(&j, r, t);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_object(&j, "totals");
    cb_json_int(&j, "palettes", (long long)r->palettes_total);
    cb_json_int(&j, "meshes", (long long)r->meshes_total);
    cb_json_int(&j, "roster", (long long)r->total);
    cb_json_object(&j, "vat");
    for (int e = 0; e < CB_VAT_ENCODINGS; ++e) cb_json_int(&j, cb_vat_encodings[e].name, (long long)r->vat_total[e]);
    cb_json_end(&j);
    if (r->failed_types) cb_json_null(&j, "over_budget"); /* unknown: the totals miss failed types */
    else cb_json_bool(&j, "over_budget", r->over_budget);
    cb_json_int(&j, "warnings", r->warnings);
    cb_json_int(&j, "failed_types", r->failed_types);
    cb_json_end(&j);
    cb_json_end(&j);
}

void cb_report_paragraph(FILE *f, const cb_report *r)
{
    char a[32], b[32];
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    uint32_t files = 0;
    for (uint32_t i = 0; i < r->type_count; ++i) files += !r->types[i].shares;
    fprintf(f, "%u type%s in %u palette%s: %s of palettes + %s of meshes; vertex animation textures of the same frames "
               "would take %.1fx the palettes. ",
            r->type_count, r->type_count == 1 ? "" : "s", files, files == 1 ? "" : "s", a, b, report_ratio(r->vat_total[0], r->palettes_total));
    report_budget_line(f, r, "", "\n");
}
