/* report_herd.c - per type, the herd the roster's budget left holds: how many instances of it
 * fit (palettes and meshes are counted in the roster's total, once; each instance adds its own
 * data) and how many vertices a frame drawing them skins, which a target's vertex rate, not its
 * memory, limits long before: beside that rate, estimated, where the target's maker states a figure. */
#include "report_parts.h"

#include <math.h>
#include <string.h>

/* Targets whose maker states a figure a vertex rate can be estimated from: the peak FP32 rate,
 * over what the shipped shader spends on one skinned vertex (docs/budget.md). Desktop, mobile
 * and WebGL profiles name no one GPU, so they state none. */
static const struct {
    const char *profile;
    double flops; /* FP32 operations a second, as stated */
    const char *source;
} stated_rates[] = {
    {"Steam Deck", 1.6e12, "Valve's Steam Deck tech specs: GPU 8 RDNA 2 CUs at 1.0-1.6 GHz, up to 1.6 TFlops FP32"},
};

/* FP32 operations runtimes/glsl/crowdbake_palette.glsl spends on a vertex with 4 influences
 * (qpos): per influence, the texel fetch's decode, the position and the normal rotated by a
 * quaternion and weighted (~60); then the instance's 3x4 transform and the projection (~60). */
enum { SKINNED_VERTEX_FLOP = 300 };
enum { FRAME_RATE = 60 };

static void find_vertex_rate(cb_report *r)
{
    const cb_target_profile *p = cb_find_profile(r->target);
    r->vertex_rate = 0, r->vertex_rate_source = NULL;
    for (size_t i = 0; p && i < sizeof stated_rates / sizeof stated_rates[0]; ++i)
        if (!strcmp(stated_rates[i].profile, p->name))
            r->vertex_rate = stated_rates[i].flops / SKINNED_VERTEX_FLOP, r->vertex_rate_source = stated_rates[i].source;
}

double report_frame_share(const cb_report *r, const cb_report_type *t)
{
    return r->vertex_rate > 0 ? t->herd_vertices / (r->vertex_rate / FRAME_RATE) : 0;
}

/* The instances the target's vertex rate skins at FRAME_RATE, each skinning all its vertices (an
 * estimate, as the rate is): what a herd can hold before the GPU, not the memory, runs out. */
double report_rate_instances(const cb_report *r, const cb_report_type *t)
{
    return r->vertex_rate > 0 && t->vertices ? floor(r->vertex_rate / FRAME_RATE / (double)t->vertices) : 0;
}

void cb_report_fill_herds(cb_report *r)
{
    find_vertex_rate(r);
    bool room = r->has_budget && !r->failed_types && r->total < r->budget_bytes;
    for (uint32_t i = 0; i < r->type_count; ++i) {
        cb_report_type *t = &r->types[i];
        t->herd_instances = room ? (r->budget_bytes - r->total) / CB_REPORT_INSTANCE_BYTES : 0;
        t->herd_vertices = (double)t->herd_instances * (double)t->vertices;
    }
}

/* "83.4 G" */
const char *report_count_text(double n, char *buf, size_t size)
{
    static const char *const units[] = {"", " k", " M", " G", " T", " P"};
    int u = 0;
    while (n >= 1000 && u < 5) n /= 1000, ++u;
    snprintf(buf, size, u ? "%.3g%s" : "%.0f%s", n, units[u]);
    return buf;
}

void report_herds_text(FILE *f, const cb_report *r)
{
    if (!r->has_budget || r->failed_types || !r->type_count) return;
    char left[32];
    cb_human_bytes(r->total < r->budget_bytes ? r->budget_bytes - r->total : 0, left, sizeof left);
    fprintf(f, "Herds: per type, the instances the budget left (%s) holds at %d B each (the shader's a_instance and a "
               "3x4 transform; palettes and meshes are in the total, each mesh once per model), and the vertices a frame "
               "drawing them skins",
            left, CB_REPORT_INSTANCE_BYTES);
    char rate[32];
    if (r->vertex_rate > 0)
        fprintf(f, ", beside %s's vertex rate at %d Hz: at most %s skinned vertices a frame, an estimate (%s, over ~%d "
                   "FP32 operations a skinned vertex; fragments share the same units, so expect less):\n",
                r->target, FRAME_RATE, report_count_text(r->vertex_rate / FRAME_RATE, rate, sizeof rate), r->vertex_rate_source,
                SKINNED_VERTEX_FLOP);
    else
        fprintf(f, " (%s states no vertex rate: compare with the target's measured draw rate):\n", r->target);
    fprintf(f, "%-14s %14s %9s %18s%s\n", "type", "instances", "vertices", "vertices a frame",
            r->vertex_rate > 0 ? "  of the rate (est.)  instances the rate skins (est.)" : "");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char n[32], v[32];
        report_count_text((double)t->herd_instances, n, sizeof n);
        report_count_text(t->herd_vertices, v, sizeof v);
        fprintf(f, "%-14s %14s %9llu %18s", t->name, n, (unsigned long long)t->vertices, v);
        if (r->vertex_rate > 0)
            fprintf(f, "  %17.3gx  %31s", report_frame_share(r, t),
                    report_count_text(report_rate_instances(r, t), n, sizeof n));
        fprintf(f, "\n");
    }
}

/* The page's line on the vertex rate: per type, the instances the target's rate skins a frame. */
void report_herds_html(FILE *f, const cb_report *r)
{
    if (!r->has_budget || r->failed_types || !r->type_count || r->vertex_rate <= 0) return;
    char n[32];
    fprintf(f, "<p>Memory is not what runs out first: %s's vertex rate skins at most <b>%s vertices</b> a frame at %d Hz, "
               "an estimate (", r->target, report_count_text(r->vertex_rate / FRAME_RATE, n, sizeof n), FRAME_RATE);
    report_html_escape(f, r->vertex_rate_source);
    fprintf(f, ", over ~%d FP32 operations a skinned vertex; fragments share the same units, so expect less): ",
            SKINNED_VERTEX_FLOP);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        fputs(i ? ", " : "", f);
        report_html_escape(f, r->types[i].name);
        fprintf(f, " <b>%s</b>", report_count_text(report_rate_instances(r, &r->types[i]), n, sizeof n));
    }
    fputs(" instances, each type alone.</p>\n", f);
}

void report_herds_json(cb_json *j, const cb_report *r, const cb_report_type *t)
{
    cb_json_object(j, "herd");
    cb_json_int(j, "instances", (long long)t->herd_instances);
    cb_json_int(j, "instance_bytes", CB_REPORT_INSTANCE_BYTES);
    cb_json_int(j, "vertices_per_frame", (long long)t->herd_vertices);
    if (r->vertex_rate > 0) {
        cb_json_number(j, "share_of_vertex_rate", report_frame_share(r, t));
        cb_json_int(j, "instances_at_vertex_rate", (long long)report_rate_instances(r, t));
    }
    cb_json_end(j);
}

/* In the budget object: the target's vertex rate, where it states one. */
void report_vertex_rate_json(cb_json *j, const cb_report *r)
{
    if (r->vertex_rate <= 0) return;
    cb_json_object(j, "vertex_rate");
    cb_json_number(j, "vertices_per_second", r->vertex_rate);
    cb_json_int(j, "frame_rate", FRAME_RATE);
    cb_json_number(j, "vertices_per_frame", r->vertex_rate / FRAME_RATE);
    cb_json_bool(j, "estimate", true);
    cb_json_int(j, "flop_per_vertex", SKINNED_VERTEX_FLOP);
    cb_json_string(j, "source", r->vertex_rate_source);
    cb_json_end(j);
}
