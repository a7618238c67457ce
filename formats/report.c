/* report.c - see report.h and docs/budget.md for every formula. */
#include "report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "json_writer.h"

void cb_human_bytes(uint64_t b, char *buf, size_t size)
{
    const char *units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double v = (double)b;
    int u = 0;
    while (v >= 1024 && u < 4) v /= 1024, ++u;
    if (u == 0) snprintf(buf, size, "%llu B", (unsigned long long)b);
    else snprintf(buf, size, v < 10 ? "%.2f %s" : v < 100 ? "%.1f %s" : "%.0f %s", v, units[u]);
}

static double per_m(double error, double height) { return height > 0 ? error / height * 1000 : 0; }

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
        return cb_fail(err, CB_ERR_INPUT, "%s:%u:%u: [budget] target \"%s\" is not a built-in profile (%s); give its vram",
                       cat->path, b->pos.line, b->pos.column, b->target, list);
    }
    r->has_budget = true;
    snprintf(r->target, sizeof r->target, "%s", b->target ? b->target : "custom");
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
    t->mesh_bytes = cb_mesh_bytes(t->vertices, t->indices);
    t->palette_error = owner->max_error;
    t->palette_visible_error = owner->visible_error;
    t->vat_error = rt->vat_error;
    t->model_height = rt->model_height;
    t->palette_over_limit = t->width > r->max_texture_size || t->height > r->max_texture_size;
    t->bones_over_limit = t->bones > r->max_bones;
}

cb_status cb_report_build(const cb_catalog *cat, const cb_roster *roster, cb_report *r, cb_error *err)
{
    memset(r, 0, sizeof *r);
    if (resolve_budget(cat, r, err)) return err->status;
    r->types = calloc(roster->type_count ? roster->type_count : 1, sizeof *r->types);
    if (!r->types) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; i < roster->type_count; ++i) {
        if (roster->types[i].outcome == CB_TYPE_FAILED) continue;
        cb_report_type *t = &r->types[r->type_count++];
        fill_type(roster, i, r, t);
        if (!t->shares) r->palettes_total += t->palette_bytes; /* a shared palette is one texture */
        r->meshes_total += t->mesh_bytes;
        for (int e = 0; e < CB_VAT_ENCODINGS; ++e) r->vat_total[e] += t->vat_bytes[e];
        r->warnings += t->palette_over_limit + t->bones_over_limit + !t->vat_fits;
    }
    r->total = r->palettes_total + r->meshes_total;
    r->over_budget = r->has_budget && r->total > r->budget_bytes;
    return CB_OK;
}

void cb_report_free(cb_report *r)
{
    free(r->types);
    memset(r, 0, sizeof *r);
}

/* ---- shared pieces of the renderings ---- */

static const char *notes(const cb_report_type *t, char *buf, size_t size)
{
    buf[0] = '\0';
    if (t->shares) snprintf(buf + strlen(buf), size - strlen(buf), "shares %s's palette; ", t->shares);
    if (t->palette_over_limit) snprintf(buf + strlen(buf), size - strlen(buf), "PALETTE OVER TEXTURE LIMIT; ");
    if (!t->vat_fits) snprintf(buf + strlen(buf), size - strlen(buf), "VAT over texture limit; ");
    if (t->bones_over_limit) snprintf(buf + strlen(buf), size - strlen(buf), "BONES OVER SHADER LIMIT; ");
    size_t n = strlen(buf);
    if (n >= 2) buf[n - 2] = '\0';
    return buf;
}

static double ratio(uint64_t a, uint64_t b) { return b ? (double)a / b : 0; }

static void budget_line(FILE *f, const cb_report *r, const char *bold)
{
    char total[32], budget[32], vram[32], vat[32];
    cb_human_bytes(r->total, total, sizeof total);
    cb_human_bytes(r->vat_total[0] + r->meshes_total, vat, sizeof vat);
    if (!r->has_budget) {
        fprintf(f, "Roster: %s of palettes and meshes (as VAT: %s); no [budget] in the catalog.\n", total, vat);
        return;
    }
    cb_human_bytes(r->budget_bytes, budget, sizeof budget);
    cb_human_bytes(r->vram_bytes, vram, sizeof vram);
    fprintf(f, "%sRoster: %s = %.2f%% of the %s crowd budget (%s = %.0f%% of %s)%s; as VAT (RGBA16F + RGBA8): %s = %.2f%%%s.%s\n",
            bold, total, 100.0 * r->total / r->budget_bytes, r->target, budget, r->crowd_share * 100, vram,
            r->over_budget ? " — OVER BUDGET" : "", vat, 100.0 * (r->vat_total[0] + r->meshes_total) / r->budget_bytes,
            r->vat_total[0] + r->meshes_total > r->budget_bytes ? ", over budget" : "", bold);
}

/* ---- terminal ---- */

void cb_report_text(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], note[256];
    fprintf(f, "%-14s %6s %7s %9s %-12s %10s %10s %7s %10s %9s %9s %9s  %s\n", "type", "bones", "frames", "vertices",
            "palette", "bytes", "VAT 16F+8", "VAT/pal", "mesh", "enc mm/m", "seen mm/m", "VAT mm/m", "notes");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char enc[32];
        snprintf(enc, sizeof enc, "%s/%s", cb_layout_name(t->layout), cb_precision_name(t->precision));
        cb_human_bytes(t->palette_bytes, a, sizeof a);
        cb_human_bytes(t->vat_bytes[0], b, sizeof b);
        cb_human_bytes(t->mesh_bytes, c, sizeof c);
        fprintf(f, "%-14s %6u %7u %9llu %-12s %10s %10s %6.1fx %10s %9.3f %9.3f %9.3f  %s\n", t->name, t->bones, t->frames,
                (unsigned long long)t->vertices, enc, a, b, ratio(t->vat_bytes[0], t->palette_bytes), c,
                per_m(t->palette_error, t->model_height), per_m(t->palette_visible_error, t->model_height),
                per_m(t->vat_error, t->model_height), notes(t, note, sizeof note));
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
                fprintf(f, " %12s", r->types[i].encoding_bytes[l][p] ? a : "too big");
            }
        fputc('\n', f);
    }
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    fprintf(f, "\nPalettes %s (shared palettes once) + meshes %s. VAT instead of palettes:", a, b);
    for (int e = 0; e < CB_VAT_ENCODINGS; ++e) {
        cb_human_bytes(r->vat_total[e], c, sizeof c);
        fprintf(f, "%s %s %s (%.1fx)", e ? "," : "", cb_vat_encodings[e].name, c, ratio(r->vat_total[e], r->palettes_total));
    }
    fputs(".\n", f);
    budget_line(f, r, "");
    if (r->warnings) fprintf(f, "%u warning%s (see notes).\n", r->warnings, r->warnings == 1 ? "" : "s");
}

/* ---- Markdown ---- */

void cb_report_markdown(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], note[256];
    fputs("## crowdbake roster report\n\n", f);
    budget_line(f, r, "**");
    fputs("\n| type | bones | frames | vertices | palette | bytes | VAT RGBA16F+RGBA8 | VAT / palette | mesh | palette encoding "
          "error mm/m | palette visible error mm/m | VAT error mm/m | notes |\n|---|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|---|\n",
          f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        cb_human_bytes(t->palette_bytes, a, sizeof a);
        cb_human_bytes(t->vat_bytes[0], b, sizeof b);
        cb_human_bytes(t->mesh_bytes, c, sizeof c);
        fprintf(f, "| %s | %u | %u | %llu | %s/%s | %s | %s | %.1f× | %s | %.3f | %.3f | %.3f | %s |\n", t->name, t->bones,
                t->frames, (unsigned long long)t->vertices, cb_layout_name(t->layout), cb_precision_name(t->precision), a, b,
                ratio(t->vat_bytes[0], t->palette_bytes), c, per_m(t->palette_error, t->model_height),
                per_m(t->palette_visible_error, t->model_height), per_m(t->vat_error, t->model_height),
                notes(t, note, sizeof note));
    }
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    cb_human_bytes(r->vat_total[0], c, sizeof c);
    fprintf(f, "| **total** | | | | | **%s** | **%s** | %.1f× | %s | | | | |\n", a, c, ratio(r->vat_total[0], r->palettes_total), b);
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
        cb_json_int(&j, "frames", t->frames);
        cb_json_int(&j, "vertices", (long long)t->vertices);
        cb_json_int(&j, "indices", (long long)t->indices);
        cb_json_object(&j, "palette");
        cb_json_string(&j, "layout", cb_layout_name(t->layout));
        cb_json_string(&j, "precision", cb_precision_name(t->precision));
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
        cb_json_number(&j, "ratio_to_palette", ratio(t->vat_bytes[0], t->palette_bytes));
        cb_json_end(&j);
        cb_json_int(&j, "mesh_bytes", (long long)t->mesh_bytes);
        cb_json_number(&j, "model_height", t->model_height);
        cb_json_bool(&j, "palette_over_texture_limit", t->palette_over_limit);
        cb_json_bool(&j, "bones_over_limit", t->bones_over_limit);
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
    cb_json_bool(&j, "over_budget", r->over_budget);
    cb_json_int(&j, "warnings", r->warnings);
    cb_json_end(&j);
    cb_json_end(&j);
}

/* ---- HTML with an SVG chart ---- */

static void html_escape(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else if (*s == '"') fputs("&quot;", f);
        else fputc(*s, f);
    }
}

/* Two stacks, palettes and VAT, each a segment per type, on top a segment for the meshes: both
 * stack to a roster total. A dashed line marks the budget. */
static void svg_chart(FILE *f, const cb_report *r)
{
    static const char *colors[] = {"#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948", "#b07aa1", "#ff9da7"};
    const double H = 360, top = 30, left = 90, bar = 120, gap = 90;
    double max = (double)(r->vat_total[0] + r->meshes_total);
    if ((double)r->budget_bytes > max && r->has_budget) max = (double)r->budget_bytes;
    if (max <= 0) max = 1;
    double scale = H / (max * 1.05);
    fprintf(f, "<svg id=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" role=\"img\" "
               "aria-label=\"palette and VAT bytes per type against the budget\">\n",
            left + 2 * bar + 2 * gap + 220, H + top + 50);
    fprintf(f, "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"#333\"/>\n", left - 10, top + H,
            left + 2 * bar + gap + 20, top + H);
    const char *stacks[2] = {"palette", "vat"};
    for (int s = 0; s < 2; ++s) {
        double x = left + s * (bar + gap), y = top + H;
        for (uint32_t i = 0; i <= r->type_count; ++i) {
            bool mesh = i == r->type_count;
            const cb_report_type *t = mesh ? NULL : &r->types[i];
            uint64_t bytes = mesh ? r->meshes_total : s == 0 ? (t->shares ? 0 : t->palette_bytes) : t->vat_bytes[0];
            double h = bytes * scale < 1 ? 1 : bytes * scale; /* every segment stays visible */
            y -= h;
            char size[32];
            cb_human_bytes(bytes, size, sizeof size);
            fprintf(f, "<rect class=\"segment\" data-stack=\"%s\" data-type=\"", stacks[s]);
            html_escape(f, mesh ? "(meshes)" : t->name);
            fprintf(f, "\" data-bytes=\"%llu\" x=\"%.1f\" y=\"%.1f\" width=\"%.0f\" height=\"%.1f\" fill=\"%s\"><title>",
                    (unsigned long long)bytes, x, y, bar, h, mesh ? "#999" : colors[i % 8]);
            html_escape(f, mesh ? "meshes" : t->name);
            fprintf(f, ": %s</title></rect>\n", size);
        }
        char total[32];
        cb_human_bytes(s == 0 ? r->total : r->vat_total[0] + r->meshes_total, total, sizeof total);
        fprintf(f, "<text x=\"%.1f\" y=\"%.0f\" text-anchor=\"middle\">%s</text>\n", x + bar / 2, top + H + 20,
                s == 0 ? "bone-matrix palettes" : "VAT (RGBA16F + RGBA8)");
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" class=\"total\">%s</text>\n", x + bar / 2, y - 6, total);
    }
    if (r->has_budget) {
        double y = top + H - r->budget_bytes * scale;
        char b[32];
        cb_human_bytes(r->budget_bytes, b, sizeof b);
        fprintf(f, "<line class=\"budget\" x1=\"%.0f\" y1=\"%.1f\" x2=\"%.0f\" y2=\"%.1f\" stroke=\"#c00\" "
                   "stroke-dasharray=\"6 4\" stroke-width=\"2\"/>\n<text x=\"%.0f\" y=\"%.1f\" fill=\"#c00\">budget %s</text>\n",
                left - 10, y, left + 2 * bar + gap + 20, y, left + 2 * bar + gap + 26, y + 4, b);
    }
    double ly = top;
    for (uint32_t i = 0; i < r->type_count; ++i, ly += 18) {
        fprintf(f, "<rect x=\"%.0f\" y=\"%.0f\" width=\"12\" height=\"12\" fill=\"%s\"/><text x=\"%.0f\" y=\"%.0f\">",
                left + 2 * bar + 2 * gap + 20, ly, colors[i % 8], left + 2 * bar + 2 * gap + 38, ly + 11);
        html_escape(f, r->types[i].name);
        fputs("</text>\n", f);
    }
    fputs("</svg>\n", f);
}

void cb_report_html(FILE *f, const cb_report *r)
{
    fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>crowdbake roster report</title>\n"
          "<style>body{font:14px system-ui,sans-serif;margin:2em;color:#222}table{border-collapse:collapse}"
          "td,th{padding:4px 10px;border-bottom:1px solid #ddd;text-align:right}td:first-child,th:first-child{text-align:left}"
          ".over{color:#c00;font-weight:bold}svg text{font:12px system-ui,sans-serif}</style></head><body>\n"
          "<h1>crowdbake roster report</h1>\n<p", f);
    fputs(r->over_budget ? " class=\"over\">" : ">", f);
    budget_line(f, r, "");
    fputs("</p>\n", f);
    svg_chart(f, r);
    fputs("<table><tr><th>type</th><th>bones</th><th>frames</th><th>vertices</th><th>palette</th><th>bytes</th>"
          "<th>VAT RGBA16F+RGBA8</th><th>VAT / palette</th><th>mesh</th><th>palette encoding error mm/m</th><th>palette visible error mm/m</th><th>VAT mm/m</th><th>notes</th></tr>\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char a[32], b[32], c[32], note[256];
        cb_human_bytes(t->palette_bytes, a, sizeof a);
        cb_human_bytes(t->vat_bytes[0], b, sizeof b);
        cb_human_bytes(t->mesh_bytes, c, sizeof c);
        fputs("<tr><td>", f);
        html_escape(f, t->name);
        fprintf(f, "</td><td>%u</td><td>%u</td><td>%llu</td><td>%s/%s</td><td>%s</td><td>%s</td><td>%.1f×</td><td>%s</td>"
                   "<td>%.3f</td><td>%.3f</td><td>%.3f</td><td>",
                t->bones, t->frames, (unsigned long long)t->vertices, cb_layout_name(t->layout), cb_precision_name(t->precision),
                a, b, ratio(t->vat_bytes[0], t->palette_bytes), c, per_m(t->palette_error, t->model_height),
                per_m(t->palette_visible_error, t->model_height), per_m(t->vat_error, t->model_height));
        html_escape(f, notes(t, note, sizeof note));
        fputs("</td></tr>\n", f);
    }
    fputs("</table>\n<p>Formulas and target profiles: docs/budget.md in the crowdbake repository.</p>\n</body></html>\n", f);
}

void cb_report_paragraph(FILE *f, const cb_report *r)
{
    char a[32], b[32];
    cb_human_bytes(r->palettes_total, a, sizeof a);
    cb_human_bytes(r->meshes_total, b, sizeof b);
    uint32_t files = 0;
    for (uint32_t i = 0; i < r->type_count; ++i) files += !r->types[i].shares;
    fprintf(f, "%u types in %u palette%s: %s of palettes + %s of meshes; vertex animation textures of the same frames "
               "would take %.1fx the palettes. ",
            r->type_count, files, files == 1 ? "" : "s", a, b, ratio(r->vat_total[0], r->palettes_total));
    budget_line(f, r, "");
}
