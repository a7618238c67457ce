/* report.h - the VAT comparison and VRAM budget report of a baked roster: exact bytes from the
 * palettes as written, every encoding side by side, VAT sizes and errors, mesh buffers, limits,
 * and the roster's total against its budget. Terminal, Markdown, JSON and an HTML page. */
#ifndef CB_REPORT_H
#define CB_REPORT_H

#include <stdio.h>

#include "crowdbake/budget.h"
#include "report_runtime.h"
#include "roster/roster.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A state that follows the instance's speed: its ground speed and its feet's slide there. */
typedef struct cb_report_gait {
    const char *state;
    char clip[128];
    double ground_speed;            /* model units/s at rate 1 */
    bool stride;                    /* measured on planted feet (else the root's travel) */
    double slide_mean, slide_worst; /* shares of the ground speed; the mean after the per-row travel where it has one */
    bool row_travel;                /* the clip carries per-row travel offsets */
    double slide_without;           /* with row_travel: the mean slide without them */
    bool slides;                    /* cb_herd_slide.warn: the asset's feet slide at any rate */
} cb_report_gait;

typedef struct cb_report_type {
    const char *name;
    const char *shares;                 /* the owner's name when the palette is shared */
    uint32_t bones, frames;
    uint64_t vertices, indices;
    cb_layout layout;
    cb_precision precision;
    bool local_rows;                    /* the .pal's rows in each bone's parent frame (bone_space "local") */
    uint32_t width, height, blocks;     /* the palette as written */
    uint64_t palette_bytes;             /* its texture bytes (counted once per file in totals) */
    uint64_t encoding_bytes[3][3];      /* [layout][precision] at the target's texture limit; 0: does not fit */
    uint64_t vat_bytes[CB_VAT_ENCODINGS];
    bool vat_fits;                      /* at the target's texture limit */
    cb_texture_geometry vat_geometry;
    uint64_t mesh_bytes;
    const char *mesh_of;                /* an earlier type on the same model: the mesh is counted there, once */
    uint64_t herd_instances;            /* with a budget: instances the budget left holds (report_herd.c) */
    double herd_vertices;               /* vertices skinned a frame drawing that herd */
    double palette_error, vat_error, model_height; /* model units; palette_error: the encoding's, at the baked rows */
    double palette_visible_error; /* the palette as the runtime plays it: encoding and the blend of two rows */
    bool palette_over_limit, bones_over_limit;
    cb_report_runtime runtime;          /* with cb_report_add_runtime: meshes, batch and transition bytes */
    uint32_t roster_index;
    uint32_t gait_count;
    cb_report_gait *gaits;              /* the type's states that follow the speed */
    const cb_warnings *bake_warnings;   /* the roster's for the type (owned by the roster): the page lists them */
} cb_report_type;

typedef struct cb_report {
    uint32_t type_count;
    cb_report_type *types;
    bool has_budget;
    char target[128];
    const char *profile_source;
    uint64_t vram_bytes, budget_bytes;  /* budget = vram x crowd_share */
    double crowd_share;
    uint32_t max_texture_size, max_bones;
    uint64_t palettes_total, meshes_total, total, vat_total[CB_VAT_ENCODINGS];
    bool over_budget;                   /* false too when failed_types > 0: then the verdict is unknown */
    uint32_t warnings;
    uint32_t failed_types;              /* types that did not bake: the totals leave them out */
    bool single_model;                  /* `report MODEL`: the budget comes from --target, not a catalog */
    /* The target's vertex rate, skinned vertices a second: an estimate from a figure its maker
     * states (report_herd.c, docs/budget.md); 0 where the target states none. */
    double vertex_rate;
    const char *vertex_rate_source;
} cb_report;

cb_status cb_report_build(const cb_catalog *catalog, const cb_roster *roster, cb_report *out, cb_error *err);
void cb_report_free(cb_report *report);
/* Per type, the herd the budget left holds (report_herd.c): its instances at
 * CB_REPORT_INSTANCE_BYTES each (palettes and meshes are in the roster's total already) and the
 * vertices it skins a frame. */
enum { CB_REPORT_INSTANCE_BYTES = 16 + 48 }; /* the shipped shader's vec4 a_instance and a 3x4 transform */
void cb_report_fill_herds(cb_report *report);
/* The runtime section (report_runtime.h): re-reads every type's model and LODs and measures
 * their runtime meshes (seconds on a large roster). `report` adds it; the bake's closing paragraph does not need it. */
void cb_report_add_runtime(const cb_roster *roster, cb_report *r, FILE *progress /* a line per type, or NULL */);

void cb_report_text(FILE *out, const cb_report *r);
void cb_report_markdown(FILE *out, const cb_report *r);
void cb_report_json(FILE *out, const cb_report *r);
/* A self-contained page (no network, no script): per type its share of the budget on a log
 * scale (palette and mesh, and a VAT instead), how many times the budget holds it and what
 * would shrink it; every encoding; the roster against every built-in target. */
void cb_report_html(FILE *out, const cb_report *r);
/* One paragraph: what the catalog bake ends with. */
void cb_report_paragraph(FILE *out, const cb_report *r);
/* "1.6 MiB" */
void cb_human_bytes(uint64_t bytes, char *buf, size_t size);

#ifdef __cplusplus
}
#endif

#endif
