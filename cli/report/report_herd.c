/* report_herd.c - per type, the herd the roster's budget left holds: how many instances of it
 * fit (palettes and meshes are counted in the roster's total, once; each instance adds its own
 * data) and how many vertices a frame drawing them skins, which a target's vertex rate, not its
 * memory, limits long before. */
#include "report_parts.h"

#include <math.h>
#include <string.h>

void cb_report_fill_herds(cb_report *r)
{
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
               "drawing them skins (%s states no vertex rate: compare with the target's measured draw rate):\n",
            left, CB_REPORT_INSTANCE_BYTES, r->target);
    fprintf(f, "%-14s %14s %9s %18s\n", "type", "instances", "vertices", "vertices a frame");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_type *t = &r->types[i];
        char n[32], v[32];
        report_count_text((double)t->herd_instances, n, sizeof n);
        report_count_text(t->herd_vertices, v, sizeof v);
        fprintf(f, "%-14s %14s %9llu %18s\n", t->name, n, (unsigned long long)t->vertices, v);
    }
}

void report_herds_json(cb_json *j, const cb_report_type *t)
{
    cb_json_object(j, "herd");
    cb_json_int(j, "instances", (long long)t->herd_instances);
    cb_json_int(j, "instance_bytes", CB_REPORT_INSTANCE_BYTES);
    cb_json_int(j, "vertices_per_frame", (long long)t->herd_vertices);
    cb_json_end(j);
}
