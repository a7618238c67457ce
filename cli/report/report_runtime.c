/* report_runtime.c - see report_runtime.h. */
#include "report/report_runtime.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/mesh.h"
#include "crowdbake/gltf.h"
#include "crowdbake_pal.h" /* XXH64 */
#include "report/report.h"
#include "report_parts.h"

static uint32_t pick_skin(const cb_model *m)
{
    for (uint32_t s = 0; s < m->skin_count; ++s)
        if (cb_model_skin_vertex_count(m, (int32_t)s) > 0) return s;
    return 0;
}

/* One runtime mesh of `mesh_model` (joints through `remap`) measured with the palette model. */
static cb_status measure_mesh(cb_sampler *s, const cb_model *mesh_model, const uint32_t *remap, uint32_t lod,
                              uint32_t influences, uint32_t texels_per_bone, cb_report_mesh *out, cb_error *err)
{
    const cb_model *pm = cb_sampler_model(s);
    int32_t skin = (int32_t)pick_skin(mesh_model);
    cb_mesh_options o = {influences, true, false, 1, remap, pm->skins[cb_sampler_skin(s)].joint_count};
    cb_mesh mesh;
    cb_mesh_error e;
    cb_status rc = cb_mesh_build_measured(s, mesh_model, skin, &o, 30, CB_REPORT_MAX_QUANTIZATION_ERROR, &mesh, &e, err);
    if (rc) return rc;
    memset(out, 0, sizeof *out);
    out->lod = lod, out->influences = influences, out->error = e.max, out->height = e.height;
    out->fetches = influences * texels_per_bone * 2;
    out->weight_bits = mesh.weight_scale == 255 ? 8 : 16;
    cb_mesh_bytes(&mesh, &out->vertex_bytes, &out->index_bytes);
    out->vertices = cb_model_skin_vertex_count(mesh_model, skin);
    out->source_bytes = cb_model_skin_mesh_bytes(mesh_model, skin);
    cb_mesh_free(&mesh);
    return rc;
}

/* A pre-baked transition into each loop from every other loop, CB_REPORT_TRANSITION_SECONDS
 * long at the destination's rate (a one-shot ends, so it needs none). */
static void transitions(const cb_roster_type *t, const cb_roster_type *owner, cb_report_runtime *out)
{
    uint64_t rows = 0, row_bytes = (uint64_t)owner->bones * cb_layout_texels_per_bone(owner->layout) *
                                   cb_precision_texel_bytes(owner->precision);
    for (uint32_t c = 0; c < t->clip_count; ++c) out->loops += t->clips[c].loops;
    for (uint32_t c = 0; c < t->clip_count; ++c)
        if (t->clips[c].loops) rows += (uint64_t)(out->loops - 1) * (uint64_t)(lround(CB_REPORT_TRANSITION_SECONDS * t->clips[c].fps) + 1);
    out->transition_bytes = rows * row_bytes;
}

/* What a type's runtime meshes depend on: its model's and LODs' bytes (source hashes), the LODs'
 * influences and the texels a bone takes. Types of equal keys have equal meshes. */
static uint64_t meshes_key(const cb_model *m, cb_model *const *lods, const cb_catalog_animal *an, uint32_t tpb)
{
    cbpal_xxh64_state h;
    cbpal_xxh64_init(&h);
    uint64_t head[3] = {m->source_hash, tpb, an->lod_count};
    cbpal_xxh64_update(&h, head, sizeof head);
    for (uint32_t l = 0; l < an->lod_count; ++l) {
        uint64_t lod[2] = {lods[l]->source_hash, an->lod_max_influences ? an->lod_max_influences[l] : 4};
        cbpal_xxh64_update(&h, lod, sizeof lod);
    }
    return cbpal_xxh64_digest(&h);
}

/* The model's meshes at 4, 2 and 1 influences, the batch's bytes and each LOD's mesh. */
static void measure_meshes(cb_sampler *s, const cb_model *m, cb_model *const *lods, const cb_catalog_animal *an,
                           uint32_t tpb, cb_report_runtime *out, cb_error *err)
{
    for (uint32_t inf = 4; inf >= 1 && !err->status; inf /= 2)
        measure_mesh(s, m, NULL, 0, inf, tpb, &out->meshes[out->mesh_count++], err);
    if (!err->status) { /* the batch, priced on the model's own mesh (4 influences, quantized) */
        cb_mesh one;
        cb_mesh_options o = {4, true, out->meshes[0].weight_bits == 16, 1, NULL, m->skins[cb_sampler_skin(s)].joint_count};
        if (!cb_mesh_build(m, cb_sampler_skin(s), &o, &one, err)) {
            uint64_t vb, ib;
            cb_mesh_batch_bytes(&one, CB_REPORT_BATCH, &vb, &ib);
            out->batch_bytes = vb + ib;
            cb_mesh_bytes(&one, &vb, &ib);
            out->instanced_bytes = vb + ib + 16ull * CB_REPORT_BATCH;
            cb_mesh_free(&one);
        }
    }
    for (uint32_t l = 0; l < an->lod_count && !err->status; ++l) {
        const cb_model *lod = lods[l];
        uint32_t *remap = calloc(lod->skins[pick_skin(lod)].joint_count, sizeof *remap);
        uint32_t inf = an->lod_max_influences ? an->lod_max_influences[l] : 4;
        if (remap && !cb_lod_remap(m, cb_sampler_skin(s), lod, (int32_t)pick_skin(lod), remap, err))
            measure_mesh(s, lod, remap, l + 1, inf, tpb, &out->meshes[out->mesh_count++], err);
        else if (!remap)
            cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        free(remap);
    }
}

/* A type measured before with the same key: its meshes copied (true), not measured again. */
static bool measured_before(report_mesh_memo *memo, uint64_t key, cb_report_runtime *out)
{
    for (uint32_t i = 0; memo && i < memo->count; ++i) {
        const cb_report_runtime *had = memo->items[i].runtime;
        if (memo->items[i].key != key) continue;
        memcpy(out->meshes, had->meshes, had->mesh_count * sizeof *out->meshes);
        out->mesh_count = had->mesh_count, out->batch_bytes = had->batch_bytes;
        out->instanced_bytes = had->instanced_bytes;
        return true;
    }
    return false;
}

static cb_status load_lods(const cb_catalog_animal *an, cb_model **lods, cb_error *err)
{
    for (uint32_t l = 0; l < an->lod_count && !err->status; ++l) lods[l] = cb_gltf_load(an->lods[l], NULL, err);
    return err->status;
}

cb_status cb_report_runtime_measure(const cb_roster_type *t, const cb_roster_type *owner, report_mesh_memo *memo,
                                    cb_report_runtime *out, cb_error *err)
{
    memset(out, 0, sizeof *out);
    const cb_catalog_animal *an = t->animal;
    cb_model *m = cb_gltf_load(an->model, NULL, err);
    if (!m) return err->status;
    out->meshes = calloc(3 + an->lod_count, sizeof *out->meshes);
    cb_model **lods = calloc(an->lod_count + 1, sizeof *lods);
    cb_sampler *s = out->meshes && lods ? cb_sampler_create(m, (int32_t)pick_skin(m), err) : NULL;
    if (!out->meshes || !lods) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint32_t tpb = cb_layout_texels_per_bone(owner->layout);
    if (s && !load_lods(an, lods, err)) {
        uint64_t key = meshes_key(m, lods, an, tpb);
        if (!measured_before(memo, key, out)) {
            measure_meshes(s, m, lods, an, tpb, out, err);
            if (memo && !err->status) memo->items[memo->count++] = (report_mesh_memo_item){key, out};
        }
    }
    transitions(t, owner, out);
    if (s && !err->status && t == owner) report_measure_half_rate(s, owner, out);
    for (uint32_t l = 0; lods && l < an->lod_count; ++l) cb_model_free(lods[l]);
    free(lods);
    cb_sampler_free(s);
    cb_model_free(m);
    out->measured = !err->status;
    return err->status;
}

void cb_report_runtime_free(cb_report_runtime *rt)
{
    free(rt->meshes);
    memset(rt, 0, sizeof *rt);
}

static double mm(const cb_report_mesh *m) { return cb_mm_per_m(m->error, m->height); }

static void mesh_label(const cb_report_mesh *m, char *buf, size_t size)
{
    if (m->lod) snprintf(buf, size, "LOD %u, %u infl., u%u weights", m->lod, m->influences, m->weight_bits);
    else snprintf(buf, size, "model, %u infl., u%u weights", m->influences, m->weight_bits);
}

static bool any_measured(const cb_report *r)
{
    for (uint32_t i = 0; i < r->type_count; ++i)
        if (r->types[i].runtime.measured) return true;
    return false;
}

void cb_report_runtime_text(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], label[64];
    if (!any_measured(r)) return;
    fprintf(f, "\nRuntime meshes (crowdbake mesh --quantize; error: extra vertex error vs 4 influences, at 30 fps):\n"
               "%-14s %-28s %9s %11s %11s %10s %8s\n", "type", "mesh", "vertices", "buffers", "in file", "error mm/m", "fetches");
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].runtime.mesh_count; ++k) {
            const cb_report_mesh *m = &r->types[i].runtime.meshes[k];
            mesh_label(m, label, sizeof label);
            cb_human_bytes(m->vertex_bytes + m->index_bytes, a, sizeof a);
            cb_human_bytes(m->source_bytes, b, sizeof b);
            fprintf(f, "%-14s %-28s %9llu %11s %11s %10.3f %8u\n", r->types[i].name, label, (unsigned long long)m->vertices, a, b,
                    mm(m), m->fetches);
        }
    fprintf(f, "\n%-14s %16s %16s %7s %24s %s\n", "type", "batch of " CB_REPORT_STR(CB_REPORT_BATCH), "instanced", "ratio",
            "pre-baked transitions", "(a runtime cross-fade needs none)");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_runtime *rt = &r->types[i].runtime;
        if (!rt->measured) continue;
        cb_human_bytes(rt->batch_bytes, a, sizeof a);
        cb_human_bytes(rt->instanced_bytes, b, sizeof b);
        cb_human_bytes(rt->transition_bytes, c, sizeof c);
        fprintf(f, "%-14s %16s %16s %6.0fx %13s for %2u loops\n", r->types[i].name, a, b,
                rt->instanced_bytes ? (double)rt->batch_bytes / rt->instanced_bytes : 0, c, rt->loops);
    }
    fputc('\n', f);
}

void cb_report_runtime_markdown(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], label[64];
    if (!any_measured(r)) return;
    fputs("\n### Runtime meshes, batches and transitions\n\n| type | mesh | vertices | buffers (quantized) | in its file | extra "
          "error mm/m vs 4 influences | texel fetches per vertex |\n|---|---|--:|--:|--:|--:|--:|\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].runtime.mesh_count; ++k) {
            const cb_report_mesh *m = &r->types[i].runtime.meshes[k];
            mesh_label(m, label, sizeof label);
            cb_human_bytes(m->vertex_bytes + m->index_bytes, a, sizeof a);
            cb_human_bytes(m->source_bytes, b, sizeof b);
            fprintf(f, "| %s | %s | %llu | %s | %s | %.3f | %u |\n", r->types[i].name, label, (unsigned long long)m->vertices, a,
                    b, mm(m), m->fetches);
        }
    fputs("\n| type | batch of " CB_REPORT_STR(CB_REPORT_BATCH) " copies | instanced | pre-baked transitions (" CB_REPORT_STR(
              CB_REPORT_TRANSITION_SECONDS) " s each) a runtime cross-fade saves |\n|---|--:|--:|--:|\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_runtime *rt = &r->types[i].runtime;
        if (!rt->measured) continue;
        cb_human_bytes(rt->batch_bytes, a, sizeof a);
        cb_human_bytes(rt->instanced_bytes, b, sizeof b);
        cb_human_bytes(rt->transition_bytes, c, sizeof c);
        fprintf(f, "| %s | %s | %s | %s for %u loops |\n", r->types[i].name, a, b, c, rt->loops);
    }
}

void cb_report_runtime_json(cb_json *j, const cb_report_runtime *rt)
{
    if (!rt->measured) return;
    cb_json_object(j, "runtime");
    cb_json_array(j, "meshes");
    for (uint32_t k = 0; k < rt->mesh_count; ++k) {
        const cb_report_mesh *m = &rt->meshes[k];
        cb_json_object(j, NULL);
        cb_json_int(j, "lod", m->lod);
        cb_json_int(j, "max_influences", m->influences);
        cb_json_int(j, "vertices", (long long)m->vertices);
        cb_json_int(j, "vertex_bytes", (long long)m->vertex_bytes);
        cb_json_int(j, "index_bytes", (long long)m->index_bytes);
        cb_json_int(j, "source_bytes", (long long)m->source_bytes);
        cb_json_number(j, "error", m->error);
        cb_json_number(j, "error_mm_per_m", mm(m));
        cb_json_int(j, "texel_fetches_per_vertex", m->fetches);
        cb_json_int(j, "weight_bits", m->weight_bits);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_object(j, "batch");
    cb_json_int(j, "copies", CB_REPORT_BATCH);
    cb_json_int(j, "batched_bytes", (long long)rt->batch_bytes);
    cb_json_int(j, "instanced_bytes", (long long)rt->instanced_bytes);
    cb_json_end(j);
    cb_json_object(j, "crossfade");
    cb_json_int(j, "loops", rt->loops);
    cb_json_number(j, "transition_seconds", CB_REPORT_TRANSITION_SECONDS);
    cb_json_int(j, "transition_clips", (long long)rt->loops * (rt->loops ? rt->loops - 1 : 0));
    cb_json_int(j, "prebaked_transition_bytes", (long long)rt->transition_bytes);
    cb_json_end(j);
    cb_json_end(j);
}

void cb_report_runtime_html(FILE *f, const cb_report *r)
{
    char a[32], b[32], c[32], label[64];
    if (!any_measured(r)) return;
    fputs("<h2>Runtime meshes, batches and transitions</h2>\n<p>Meshes as <code>crowdbake mesh --quantize</code> writes them; "
          "the error is the extra vertex error of fewer influences against 4, over every frame of every clip at 30 fps; "
          "fewer influences fetch fewer palette texels per vertex.</p>\n<table>\n<tr><th>type</th><th>mesh</th><th>vertices"
          "</th><th>buffers</th><th>in its file</th><th>error mm/m</th><th>texel fetches</th></tr>\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i)
        for (uint32_t k = 0; k < r->types[i].runtime.mesh_count; ++k) {
            const cb_report_mesh *m = &r->types[i].runtime.meshes[k];
            mesh_label(m, label, sizeof label);
            cb_human_bytes(m->vertex_bytes + m->index_bytes, a, sizeof a);
            cb_human_bytes(m->source_bytes, b, sizeof b);
            fputs("<tr><td>", f);
            report_html_escape(f, r->types[i].name);
            fprintf(f, "</td><td>%s</td><td class=\"n\">%llu</td><td class=\"n\">%s</td><td class=\"n\">%s</td><td class=\"n\">"
                       "%.3f</td><td class=\"n\">%u</td></tr>\n", label, (unsigned long long)m->vertices, a, b, mm(m), m->fetches);
        }
    fputs("</table>\n<table>\n<tr><th>type</th><th>batch of " CB_REPORT_STR(CB_REPORT_BATCH) " copies</th><th>instanced</th>"
          "<th>pre-baked transitions</th><th>loops</th></tr>\n", f);
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_report_runtime *rt = &r->types[i].runtime;
        if (!rt->measured) continue;
        cb_human_bytes(rt->batch_bytes, a, sizeof a);
        cb_human_bytes(rt->instanced_bytes, b, sizeof b);
        cb_human_bytes(rt->transition_bytes, c, sizeof c);
        fputs("<tr><td>", f);
        report_html_escape(f, r->types[i].name);
        fprintf(f, "</td><td class=\"n\">%s</td><td class=\"n\">%s</td><td class=\"n\">%s</td><td class=\"n\">%u</td></tr>\n", a,
                b, c, rt->loops);
    }
    fputs("</table>\n<p>A runtime cross-fade (<code>cb_skin_position_crossfade</code>) blends two clips in the shader, so "
          "none of those transition bytes are needed.</p>\n", f);
}
