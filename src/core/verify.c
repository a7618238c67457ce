/* verify.c - see runtime.h: a palette against exact skinning, clip by clip (cb_verify_clip). */
#include "crowdbake/runtime.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>

#include "cb_math.h"
#include "palette_bake.h" /* palette_bake_with_facts */
#include "timed_rows.h"     /* a timed clip's rows */

/* ---- verification ---- */

typedef struct verify_ctx {
    cb_sampler *s;
    const cb_palette *p;
    const void *texels;
    const cb_palette_clip *clip;
    int32_t animation;
    double *exact_m, *run_m, *exact_v, *run_v;
    uint64_t verts;
} verify_ctx;

/* Worst and summed vertex distance at clip time t. */
static double compare_at(verify_ctx *c, double t, double *sum, uint64_t *worst_vertex)
{
    const cb_model *m = cb_sampler_model(c->s);
    int32_t skin = cb_sampler_skin(c->s);
    cb_sample_joint_matrices(c->s, c->animation, c->clip->start + t, c->exact_m);
    const cb_animation *a = &m->animations[c->animation];
    double tau = cb_root_travel_time(t, a->t1 - a->t0, c->clip->duration, c->clip->loops);
    for (uint32_t j = 0; j < c->p->bone_count; ++j) { /* in-place bakes removed this travel */
        c->exact_m[(size_t)j * 16 + 12] -= c->clip->root_velocity[0] * tau;
        c->exact_m[(size_t)j * 16 + 14] -= c->clip->root_velocity[2] * tau;
    }
    cb_instance in = cb_instance_of(c->clip); /* held rows too: verify plays what the shaders play */
    cb_runtime_matrices(c->p, c->texels, &in, t, c->run_m);
    double *e = c->exact_v, *r = c->run_v;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        cb_skin_positions(prim, c->exact_m, e);
        cb_skin_positions(prim, c->run_m, r);
        e += (size_t)prim->vertex_count * 3, r += (size_t)prim->vertex_count * 3;
    }
    double worst = 0;
    for (uint64_t v = 0; v < c->verts; ++v) {
        const double *a = c->exact_v + v * 3, *b = c->run_v + v * 3;
        double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        *sum += d;
        if (d > worst) worst = d, *worst_vertex = v;
    }
    return worst;
}

static void record(cb_clip_error *out, bool interp, double worst, uint64_t vertex, double t)
{
    double *max = interp ? &out->interp_max : &out->quant_max;
    if (worst > *max) *max = worst;
    if (worst >= out->quant_max && worst >= out->interp_max) out->worst_vertex = vertex, out->worst_time = t;
}

cb_status cb_verify_clip(cb_sampler *s, const cb_palette *p, const void *texels, uint32_t clip, int32_t animation,
                         uint32_t random_times, cb_clip_error *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    memset(out, 0, sizeof *out);
    verify_ctx c = {s, p, texels, &p->clips[clip], animation, NULL, NULL, NULL, NULL,
                    cb_model_skin_vertex_count(m, cb_sampler_skin(s))};
    if (m->skins[cb_sampler_skin(s)].joint_count != p->bone_count)
        return cb_fail(err, CB_ERR_INPUT, "%s: its skin has %u joints, the palette %u bones: not the palette of this model",
                       m->source, m->skins[cb_sampler_skin(s)].joint_count, p->bone_count);
    c.exact_m = malloc((size_t)p->bone_count * 16 * sizeof(double));
    c.run_m = malloc((size_t)p->bone_count * 16 * sizeof(double));
    c.exact_v = malloc((size_t)(c.verts ? c.verts : 1) * 3 * sizeof(double));
    c.run_v = malloc((size_t)(c.verts ? c.verts : 1) * 3 * sizeof(double));
    /* a loop without a closing key wraps; one whose closing key is slightly off is closed */
    bool closed = cb_sampler_set_baked_loop(s, animation, c.clip->loops, c.clip->start, c.clip->duration);
    if (closed && c.exact_m && c.run_m && c.exact_v && c.run_v) {
        const cb_palette_clip *cl = c.clip;
        uint32_t steps = cl->loops ? cl->frames : cl->frames - 1; /* row intervals */
        double dt = cl->fps > 0 ? 1 / cl->fps : 0, qsum = 0, isum = 0;
        uint64_t v, qn = 0, in = 0;
        /* A timed clip's rows lie on the cells its map says (NULL: row f at f dt). */
        uint32_t *cells = cl->timed ? malloc((size_t)cl->frames * sizeof *cells) : NULL;
        if (cells) timed_map_row_cells(p, texels, cl, cells), dt = cl->duration / steps;
        for (uint32_t f = 0; f < cl->frames; ++f, ++qn) {
            double t = cells ? cells[f] / cl->cell_rate : f * dt;
            record(out, false, compare_at(&c, t, &qsum, &v), v, t);
        }
        for (uint32_t f = 0; f < steps; ++f, ++in) {
            double t = cells ? (cells[f] + (f + 1 < cl->frames ? cells[f + 1] : cl->cells)) / (2 * cl->cell_rate) : (f + 0.5) * dt;
            record(out, true, compare_at(&c, t, &isum, &v), v, t);
        }
        free(cells);
        uint64_t state = 0x9E3779B97F4A7C15ull ^ clip;
        for (uint32_t i = 0; i < random_times && steps > 0; ++i, ++in) {
            state ^= state << 13, state ^= state >> 7, state ^= state << 17; /* xorshift64 */
            double t = (double)(state >> 11) / (double)(1ull << 53) * steps * dt;
            record(out, true, compare_at(&c, t, &isum, &v), v, t);
        }
        out->quant_mean = qn && c.verts ? qsum / (qn * c.verts) : 0;
        out->interp_mean = in && c.verts ? isum / (in * c.verts) : 0;
    } else {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory verifying %s", m->source);
    }
    free(c.exact_m), free(c.run_m), free(c.exact_v), free(c.run_v);
    return err->status;
}
