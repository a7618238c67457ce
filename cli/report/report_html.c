/* report_html.c - the report as one self-contained HTML page (cb_report_html). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "report_parts.h"

/* ---- HTML: the page a technical director reads ----
 *
 * It answers, for the report's target: what share of the crowd budget each type takes (its
 * palette and mesh, and a VAT of the same frames instead), how many times over the budget holds
 * it, and what would shrink it (encoding, frame rate, sharing); then the roster against every
 * built-in target. Shares span six decades (a fish is 0.002% of a console's budget, a roster can
 * be 300% of a phone's), so bars use a log scale of the share; within a bar, segments split its
 * length by bytes. Plain HTML and CSS, no script: the browser lays out the text, nothing is
 * placed by guesswork. */

void report_html_escape(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else if (*s == '"') fputs("&quot;", f);
        else fputc(*s, f);
    }
}

/* The log axis of a page: decades from lo to hi of value / reference, where the reference is
 * the budget (shares) or one byte when there is none. */
typedef struct log_axis {
    double reference;  /* bytes */
    int lo, hi;        /* decade exponents */
    bool shares;
} log_axis;

static double axis_position(const log_axis *a, uint64_t bytes) /* 0..100, % of the bar area */
{
    if (!bytes) return 0;
    double x = (log10((double)bytes / a->reference) - a->lo) / (a->hi - a->lo) * 100;
    return x < 0.5 ? 0.5 : x > 100 ? 100 : x; /* a type never vanishes */
}

static log_axis make_axis(const cb_report *r)
{
    log_axis a = {r->has_budget ? (double)r->budget_bytes : 1.0, 0, 0, r->has_budget};
    double lo = INFINITY, hi = a.shares ? 1.0 : 0; /* with a budget, 100% is always on the axis */
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        lo = fmin(lo, (double)(t->palette_bytes + t->mesh_bytes) / a.reference);
        hi = fmax(hi, (double)(t->vat_bytes[0] + t->mesh_bytes) / a.reference);
    }
    hi = fmax(hi, (double)(r->vat_total[0] + r->meshes_total) / a.reference);
    if (!(lo < INFINITY) || !(lo > 0)) lo = hi > 0 ? hi / 10 : 1;
    a.hi = (int)ceil(log10(hi) - 1e-9);
    a.lo = (int)floor(log10(lo));
    if (a.hi - a.lo > 7) a.lo = a.hi - 7; /* smaller still is drawn at the left edge */
    if (a.hi - a.lo < 2) a.lo = a.hi - 2;
    return a;
}

static void share_text(const cb_report *r, uint64_t bytes, char *buf, size_t size)
{
    char b[32];
    cb_human_bytes(bytes, b, sizeof b);
    if (!r->has_budget) snprintf(buf, size, "%s", b);
    else {
        double pct = 100.0 * (double)bytes / (double)r->budget_bytes;
        snprintf(buf, size, pct >= 10 ? "%s · %.0f%%" : pct >= 0.01 ? "%s · %.2f%%" : "%s · %.4f%%", b, pct);
    }
}

/* One bar: segments (bytes, class) splitting the length of their sum's position. */
static void html_bar(FILE *f, const cb_report *r, const log_axis *a, const char *kind, const char *type,
                     const uint64_t *bytes, const char *const *classes, int n, const char *note)
{
    uint64_t total = 0;
    for (int i = 0; i < n; ++i) total += bytes[i];
    double end = axis_position(a, total);
    char label[192];
    share_text(r, total, label, sizeof label);
    if (note) snprintf(label + strlen(label), sizeof label - strlen(label), " %s", note);
    fprintf(f, "<div class=\"track\"><div class=\"bar\" data-kind=\"%s\" data-type=\"", kind);
    report_html_escape(f, type);
    fprintf(f, "\" data-bytes=\"%llu\" style=\"width:%.2f%%\">", (unsigned long long)total, end);
    for (int i = 0; i < n; ++i)
        if (bytes[i])
            fprintf(f, "<span class=\"seg %s\" style=\"width:%.2f%%\"></span>", classes[i],
                    total ? 100.0 * (double)bytes[i] / (double)total : 0);
    /* The label sits after the bar, or inside its end when the bar nearly fills the track. */
    fprintf(f, "</div><span class=\"value%s\" style=\"%s:%.2f%%\">", end > 70 ? " inside" : "", end > 70 ? "right" : "left",
            end > 70 ? 100 - end : end);
    report_html_escape(f, label);
    fputs("</span>", f);
    if (a->shares) fprintf(f, "<span class=\"budget-line\" style=\"left:%.2f%%\"></span>", axis_position(a, (uint64_t)a->reference));
    fputs("</div>", f);
}

static void html_axis(FILE *f, const log_axis *a)
{
    fputs("<div class=\"axis\">", f);
    for (int e = a->lo; e <= a->hi; ++e) {
        double x = (double)(e - a->lo) / (a->hi - a->lo) * 100;
        char t[32];
        if (a->shares) {
            double pct = pow(10, e) * 100;
            int decimals = e >= -2 ? 0 : -2 - e; /* 10^e of the budget is 10^(e+2) % */
            snprintf(t, sizeof t, "%.*f%%", decimals, pct);
        } else { /* decades of bytes read best in SI units */
            static const char *const si[] = {"B", "kB", "MB", "GB", "TB"};
            int u = e < 0 ? 0 : e / 3 > 4 ? 4 : e / 3;
            snprintf(t, sizeof t, "%.0f %s", pow(10, e - 3 * u), si[u]);
        }
        const char *align = e == a->lo ? "first" : e == a->hi ? "last" : "mid";
        fprintf(f, "<span class=\"tick %s\" style=\"left:%.2f%%\">%s</span>", align, x, t);
    }
    fputs("</div>", f);
}

/* Bytes a type's palette would take at half its frame rate (rows halved), same encoding; 0
 * unless the palette baked at half the rates kept every clip within its max_error (measured,
 * report_half.c): the report never advises what breaks the error budget. */
static uint64_t half_rate_bytes(const cb_report *r, const cb_report_type *t)
{
    if (!t->runtime.half_rate_measured || !t->runtime.half_rate_within) return 0;
    cb_texture_geometry g;
    return cb_palette_texture_bytes(t->bones, (t->frames + 1) / 2, t->layout, t->precision, r->max_texture_size, &g);
}

/* The smallest of the nine encodings that fits the target, as "qpos/u16". */
static uint64_t smallest_encoding(const cb_report_type *t, char *name, size_t size)
{
    uint64_t best = 0;
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p)
            if (t->encoding_bytes[l][p] && report_encoding_holds(t, l, p) &&
                (!best || t->encoding_bytes[l][p] <= best)) { /* ties: the later, finer u16 */
                best = t->encoding_bytes[l][p];
                snprintf(name, size, "%s/%s", cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)p));
            }
    return best;
}

/* What would make a type smaller, one suggestion per lever, with the bytes it saves. */
static void html_fixes(FILE *f, const cb_report *r, const cb_report_type *t)
{
    char a[32], enc[32] = "";
    if (t->shares) {
        fputs("<li>shares <b>", f);
        report_html_escape(f, t->shares);
        fputs("</b>'s palette: counted once</li>", f);
        return;
    }
    uint64_t best = smallest_encoding(t, enc, sizeof enc);
    if (best && best < t->palette_bytes) {
        cb_human_bytes(t->palette_bytes - best, a, sizeof a);
        fprintf(f, "<li>%s saves %s</li>", enc, a);
    }
    uint32_t fixed_over = 0; /* clips whose fixed fps misses max_error (the bake's warnings) */
    for (uint32_t i = 0; t->bake_warnings && i < t->bake_warnings->count; ++i)
        fixed_over += strstr(t->bake_warnings->items[i].message, "which a fixed fps is not held to") != NULL;
    if (fixed_over)
        fprintf(f, "<li>leave <code>fps</code> out: %u clip%s miss%s max_error at the fixed rate (see the warnings)</li>",
                fixed_over, fixed_over == 1 ? "" : "s", fixed_over == 1 ? "es" : "");
    uint64_t half = half_rate_bytes(r, t);
    if (half && half < t->palette_bytes) {
        cb_human_bytes(t->palette_bytes - half, a, sizeof a);
        fprintf(f, "<li>half the fps saves %s and stays within max_error (%.3g mm/m measured)</li>", a,
                t->runtime.half_rate_error_mm);
    }
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *o = &r->types[i];
        if (o != t && !o->shares && o->bones == t->bones && o->frames == t->frames && strcmp(o->name, t->name) < 0) {
            fputs("<li>as large as <b>", f);
            report_html_escape(f, o->name);
            fputs("</b>: the same rig and clips would share its palette</li>", f);
            break;
        }
    }
}

/* Roster-wide: how far over, and what each lever saves over every palette (shared ones once). */
static void html_overrun(FILE *f, const cb_report *r)
{
    uint64_t over = r->total - r->budget_bytes, encodings = 0, rates = 0;
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        if (t->shares) continue;
        char enc[32];
        uint64_t best = smallest_encoding(t, enc, sizeof enc), half = half_rate_bytes(r, t);
        if (best && best < t->palette_bytes) encodings += t->palette_bytes - best;
        if (half && half < t->palette_bytes) rates += t->palette_bytes - half;
    }
    char a[32], b[32], c[32], m[32];
    cb_human_bytes(over, a, sizeof a);
    cb_human_bytes(encodings, b, sizeof b);
    cb_human_bytes(rates, c, sizeof c);
    cb_human_bytes(r->meshes_total, m, sizeof m);
    fprintf(f, "<div class=\"overrun\"><b>Over budget by %s.</b> The smallest encoding for every type saves %s%s; ", a, b,
            encodings >= over ? " (enough)" : "");
    if (rates) fprintf(f, "half the frame rate, where every clip stays within max_error, saves %s%s; ", c, rates >= over ? " (enough)" : "");
    else fputs("half the frame rate would put clips over max_error in every type (measured); ", f);
    fprintf(f, "the meshes alone take %s. ", m);
    fputs(encodings >= over || rates >= over ? "</div>\n"
                                             : "Neither is enough alone: raise <code>crowd_share</code>, pick a larger "
                                               "target or bake fewer types or clips.</div>\n", f);
}

static void html_chart(FILE *f, const cb_report *r)
{
    log_axis a = make_axis(r);
    static const char *const pal_classes[] = {"palette", "mesh"}, *const vat_classes[] = {"vat", "mesh"};
    fprintf(f, "<h2>%s</h2>\n<p class=\"legend\"><span class=\"key palette\"></span>palette <span class=\"key vat\"></span>"
               "VAT (RGBA16F + RGBA8) instead <span class=\"key mesh\"></span>mesh buffers%s</p>\n",
            a.shares ? "Share of the crowd budget (log scale)" : "Bytes per type (log scale)",
            a.shares ? " <span class=\"key budget\"></span>the budget" : "");
    if (a.shares && r->total < r->budget_bytes) {
        /* Instances cost their per-instance data only: the shipped shader's vec4 a_instance and a
         * 3x4 transform. */
        enum { INSTANCE_BYTES = 16 + 48 };
        char left[32];
        cb_human_bytes(r->budget_bytes - r->total, left, sizeof left);
        fprintf(f, "<p>Instances draw from their type's palette and mesh and add only their own data (%d B: the shader's "
                   "<code>a_instance</code> and a 3×4 transform): the %s left holds <b>%llu instances</b>.</p>\n",
                INSTANCE_BYTES, left, (unsigned long long)((r->budget_bytes - r->total) / INSTANCE_BYTES));
        report_herds_html(f, r);
    }
    fputs("<div class=\"chart\"><div class=\"row head\"><span class=\"name\"></span><span class=\"kind\"></span>", f);
    html_axis(f, &a);
    fprintf(f, "<span class=\"fits\" title=\"instances of the type the budget left holds, %d B each\">%s</span></div>\n",
            CB_REPORT_INSTANCE_BYTES, a.shares ? "instances" : "");
    for (uint32_t i = 0; i <= r->type_count; ++i) {
        bool roster = i == r->type_count;
        const cb_report_type *t = roster ? NULL : &r->types[i];
        const char *name = roster ? "whole roster" : t->name;
        uint64_t pal[2] = {roster ? r->palettes_total : t->shares ? 0 : t->palette_bytes, roster ? r->meshes_total : t->mesh_bytes};
        uint64_t vat[2] = {roster ? r->vat_total[0] : t->vat_bytes[0], pal[1]};
        for (int k = 0; k < 2; ++k) {
            fprintf(f, "<div class=\"row%s%s\"><span class=\"name\">", roster ? " total" : "", k ? " second" : "");
            if (!k) report_html_escape(f, name);
            fprintf(f, "</span><span class=\"kind\">%s</span>", k ? "as VAT" : "palette");
            char note[160] = "";
            if (!k && !roster && t->shares) snprintf(note, sizeof note, "(mesh only: the palette is %s's)", t->shares);
            html_bar(f, r, &a, k ? "vat" : "palette", name, k ? vat : pal, k ? vat_classes : pal_classes, 2,
                     note[0] ? note : NULL);
            /* The herd the budget left holds (report_herd.c), on the type's palette row. */
            if (a.shares && !k && !roster && t->herd_instances)
                fprintf(f, "<span class=\"fits\">%s</span></div>\n", report_count_text((double)t->herd_instances, note, sizeof note));
            else if (a.shares && !k && roster && r->over_budget)
                fputs("<span class=\"fits over\">over</span></div>\n", f);
            else
                fputs("<span class=\"fits\"></span></div>\n", f);
        }
    }
    fputs("</div>\n", f);
}

/* The main table: one column per entry, so a column is one line here. */
typedef struct html_column {
    const char *title;
    void (*cell)(FILE *f, const cb_report *r, const cb_report_type *t);
} html_column;

static void cell_name(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, report_html_escape(f, t->name); }
static void cell_bones(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, fprintf(f, "%u", t->bones); }
static void cell_frames(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, fprintf(f, "%u", t->frames); }
static void cell_vertices(FILE *f, const cb_report *r, const cb_report_type *t)
{
    (void)r, fprintf(f, "%llu", (unsigned long long)t->vertices);
}
static void cell_encoding(FILE *f, const cb_report *r, const cb_report_type *t)
{
    char enc[32];
    (void)r, fprintf(f, "%s", report_encoding(t, enc, sizeof enc));
}
static void cell_bytes(FILE *f, uint64_t bytes)
{
    char b[32];
    cb_human_bytes(bytes, b, sizeof b);
    fputs(b, f);
}
static void cell_palette(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, cell_bytes(f, t->palette_bytes); }
static void cell_mesh(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, cell_bytes(f, t->mesh_bytes); }
static void cell_vat(FILE *f, const cb_report *r, const cb_report_type *t) { (void)r, cell_bytes(f, t->vat_bytes[0]); }
static void cell_ratio(FILE *f, const cb_report *r, const cb_report_type *t)
{
    (void)r, fprintf(f, "%.1f×", report_ratio(t->vat_bytes[0], t->palette_bytes));
}
static void cell_pal_error(FILE *f, const cb_report *r, const cb_report_type *t)
{
    (void)r, fprintf(f, "%.3f", cb_mm_per_m(t->palette_error, t->model_height));
}
static void cell_pal_visible_error(FILE *f, const cb_report *r, const cb_report_type *t)
{
    (void)r, fprintf(f, "%.3f", cb_mm_per_m(t->palette_visible_error, t->model_height));
}

static void cell_vat_error(FILE *f, const cb_report *r, const cb_report_type *t)
{
    (void)r, fprintf(f, "%.3f", cb_mm_per_m(t->vat_error, t->model_height));
}
static void cell_fixes(FILE *f, const cb_report *r, const cb_report_type *t)
{
    fputs("<ul>", f);
    html_fixes(f, r, t);
    fputs("</ul>", f);
}

static const html_column html_columns[] = {
    {"type", cell_name},          {"bones", cell_bones},          {"rows", cell_frames},
    {"vertices", cell_vertices},  {"encoding", cell_encoding},    {"palette", cell_palette},
    {"mesh", cell_mesh},          {"VAT 16F+8", cell_vat},        {"VAT / palette", cell_ratio},
    {"palette encoding error mm/m", cell_pal_error}, {"palette visible error mm/m", cell_pal_visible_error},
    {"VAT error mm/m", cell_vat_error}, {"what would shrink it", cell_fixes},
};

static void html_table(FILE *f, const cb_report *r)
{
    fputs("<h2>Per type</h2>\n<div class=\"scroll\"><table id=\"types\"><tr>", f);
    for (size_t c = 0; c < sizeof html_columns / sizeof html_columns[0]; ++c) fprintf(f, "<th>%s</th>", html_columns[c].title);
    fputs("</tr>\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        fputs("<tr>", f);
        for (size_t c = 0; c < sizeof html_columns / sizeof html_columns[0]; ++c) {
            fputs("<td>", f);
            html_columns[c].cell(f, r, &r->types[i]);
            fputs("</td>", f);
        }
        fputs("</tr>\n", f);
    }
    fputs("</table></div>\n", f);
}

/* Every encoding: bytes and, on the same log scale as the chart, a bar per cell. */
static void html_encodings(FILE *f, const cb_report *r)
{
    log_axis a = make_axis(r);
    fprintf(f, "<h2>Every encoding</h2>\n<p>Texture bytes at the %u-texel limit%s; the bar is the share on the chart's "
               "log scale, the baked encoding is outlined.</p>\n<div class=\"scroll\"><table id=\"encodings\"><tr><th>type</th>",
            r->max_texture_size, r->has_budget ? " and share of the budget" : "");
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) fprintf(f, "<th>%s/%s</th>", cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)p));
    fputs("</tr>\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        fputs("<tr><td>", f);
        report_html_escape(f, t->name);
        fputs("</td>", f);
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                uint64_t b = t->encoding_bytes[l][p];
                bool baked = (int)t->layout == l && (int)t->precision == p;
                char label[64];
                share_text(r, b, label, sizeof label);
                char *share = strstr(label, " · "); /* bytes above, share below: narrow columns */
                if (share) *share = '\0', share += strlen(" · ");
                if (!report_encoding_holds(t, l, p)) fputs("<td class=\"enc none\">-</td>", f);
                else if (!b) fputs("<td class=\"enc none\">too big</td>", f);
                else fprintf(f, "<td class=\"enc%s\"><span class=\"mini\" style=\"width:%.1f%%\"></span>%s%s%s%s</td>",
                             baked ? " baked" : "", axis_position(&a, b), label, share ? "<br><small>" : "",
                             share ? share : "", share ? "</small>" : "");
            }
        fputs("</tr>\n", f);
    }
    fputs("</table></div>\n", f);
    if (report_has_local_rows(r))
        fputs("<p>-: local rows (the default bone space) are held in qpos with u16 or float only; <code>bone_space = "
              "\"global\"</code> for the others.</p>\n", f);
}

/* The roster against every built-in target, and the catalog's own when it is not one. */
static void html_targets(FILE *f, const cb_report *r)
{
    double share = r->has_budget ? r->crowd_share : 1;
    fprintf(f, "<h2>Other targets</h2>\n<p>The same roster against each built-in profile, %g%% of its memory for "
               "crowds.</p>\n<div class=\"scroll\"><table id=\"targets\"><tr><th>target</th><th>crowd budget</th>"
               "<th>roster</th><th>as VAT</th><th>texture limit</th><th>verdict</th></tr>\n",
            share * 100);
    for (uint32_t i = 0; i < cb_profile_count; ++i) {
        const cb_target_profile *p = &cb_profiles[i];
        uint64_t budget = (uint64_t)llround((double)p->vram_bytes * share), vat = r->vat_total[0] + r->meshes_total;
        uint32_t too_wide = 0;
        for (uint32_t k = 0; k < r->type_count; ++k)
            too_wide += r->types[k].width > p->max_texture_size || r->types[k].height > p->max_texture_size;
        char b[32];
        cb_human_bytes(budget, b, sizeof b);
        bool over = r->total > budget;
        fprintf(f, "<tr%s><td>%s</td><td>%s</td><td>%.3g%%</td><td>%.3g%%</td><td>%u</td><td class=\"%s\">%s%s</td></tr>\n",
                strcmp(p->name, r->target) == 0 ? " class=\"current\"" : "", p->name, b, 100.0 * (double)r->total / budget,
                100.0 * (double)vat / budget, p->max_texture_size, over || too_wide ? "over" : "ok",
                over ? "over budget" : too_wide ? "a palette exceeds the texture limit" : "fits",
                !over && !too_wide && vat > budget ? " (a VAT would not)" : "");
    }
    fputs("</table></div>\n", f);
}

void cb_report_html(FILE *f, const cb_report *r)
{
    fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
          "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>crowdbake roster report</title>\n"
          "<style>\n"
          "body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;max-width:1400px}\n"
          "h1{font-size:22px;margin:0 0 8px}h2{font-size:17px;margin:28px 0 8px}\n"
          ".summary{font-size:15px;padding:10px 14px;border-radius:6px;background:#eef6ee;border:1px solid #9c9}\n"
          ".summary.over,.overrun{background:#fdeeee;border:1px solid #d88;color:#900}\n"
          ".overrun{margin-top:8px;padding:10px 14px;border-radius:6px}\n"
          ".legend{display:flex;flex-wrap:wrap;gap:4px 14px;align-items:center;margin:4px 0 10px}\n"
          ".key{display:inline-block;width:14px;height:10px;margin-right:4px;vertical-align:middle}\n"
          ".palette{background:#3d6fb6}.vat{background:#e58a2c}.mesh{background:#9ab}.key.budget{background:#c00;width:3px;height:14px}\n"
          ".chart{display:grid;grid-template-columns:minmax(6em,max-content) max-content minmax(200px,1fr) max-content;column-gap:10px}\n"
          ".row{display:contents}.row>*{padding:3px 0;align-self:center}\n"
          ".row .name{font-weight:600;white-space:nowrap;overflow:hidden;text-overflow:ellipsis}\n"
          ".row.total>*{border-top:1px solid #888;padding-top:6px}.row.total.second>*{border-top:0;padding-top:3px}\n"
          ".row .kind{color:#555;font-size:12px;white-space:nowrap}\n"
          ".fits{text-align:right;white-space:nowrap;font-variant-numeric:tabular-nums}.fits.over{color:#c00;font-weight:700}\n"
          ".track{position:relative;height:20px;background:#f3f3f3}\n"
          ".bar{position:absolute;left:0;top:2px;height:16px;display:flex;min-width:2px}.seg{height:100%}\n"
          ".value{position:absolute;top:1px;font-size:12px;white-space:nowrap;padding:0 6px}\n"
          ".value.inside{color:#fff;text-shadow:0 0 2px #000}\n"
          ".axis{position:relative;height:20px;border-bottom:1px solid #999}\n"
          ".tick{position:absolute;bottom:2px;font-size:11px;color:#555;white-space:nowrap;transform:translateX(-50%)}\n"
          ".tick.first{transform:none}.tick.last{transform:translateX(-100%)}\n"
          ".budget-line{position:absolute;top:0;bottom:0;width:2px;margin-left:-1px;background:#c00}\n"
          ".scroll{overflow-x:auto}table{border-collapse:collapse}\n"
          "td,th{padding:4px 10px;border-bottom:1px solid #ddd;text-align:right;white-space:nowrap;vertical-align:top}\n"
          "td:first-child,th:first-child,#types td:last-child,#types th:last-child,#targets td:last-child,#targets th:last-child{text-align:left}\n"
          "th{font-weight:600;background:#f6f6f6;white-space:normal;vertical-align:bottom}\n"
          "#types td:last-child{white-space:normal;min-width:18em}#types ul{margin:0;padding-left:1.1em}\n"
          ".warn{color:#c00;font-weight:600}\n"
          "td.enc{position:relative;min-width:5.5em}td.enc.baked{outline:2px solid #3d6fb6;outline-offset:-2px}\n"
          ".mini{position:absolute;left:0;bottom:1px;height:3px;background:#3d6fb6;opacity:.6}\n"
          "td.none{color:#999}tr.current td{font-weight:700}td.over{color:#c00}td.ok{color:#070}\n"
          "</style></head>\n", f);
    if (r->has_budget) fprintf(f, "<body data-budget-bytes=\"%llu\">\n", (unsigned long long)r->budget_bytes);
    else fputs("<body>\n", f);
    fputs("<h1>crowdbake roster report</h1>\n<p class=\"summary", f);
    fputs(r->over_budget ? " over\">" : "\">", f);
    report_budget_line(f, r, "", "<br>\n");
    fputs("</p>\n", f);
    if (r->over_budget) html_overrun(f, r);
    html_chart(f, r);
    html_table(f, r);
    report_warnings_html(f, r);
    html_encodings(f, r);
    html_targets(f, r);
    cb_report_runtime_html(f, r);
    fputs("<p>Formulas and target profiles: docs/budget.md in the crowdbake repository.</p>\n</body></html>\n", f);
}
