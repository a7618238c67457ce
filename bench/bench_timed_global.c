/* bench_timed_global.c - what timed rows (docs/pal-format.md "Timed rows") would cost for GLOBAL
 * rows (qpos u16, sampled), measured the way the bake measures a sampled clip's visible error: the
 * encoding at every kept row, and the runtime's blend (cb_palette_blend) halfway between every two
 * adjacent kept rows, skinned over every vertex against exact skinning (issue 43 item 1, task
 * tglobal step 1: measured, not shipped).
 *
 * Each clip is baked alone, uniformly, at its key rate x M (M = 16, or the largest power of two
 * that keeps the rate within CB_FPS_LIMIT): the candidate rows are rows of that bake, so they
 * carry the bake's own sampling and u16 encoding. For every key interval (cb_key_grid_fps's grid,
 * a loop's wrap included) the fewest equal splits s in {1, 2, 4, 8, 16} (s <= M) whose
 * sub-intervals meet the budget; the clip's cells are its key steps x the largest split used, its
 * map cb_timed_map_rows of them. A JSON line per clip: rows on keys, map rows, cells, the worst
 * error, and whether every interval met the budget within the splits.
 *
 *   bench_timed_global MODEL [MAX_ERROR_MM_PER_M]   (default 1, the bake's) */
#include "bench_model.h"

#include "core/key_grid.h"

enum { MOST_SPLITS = 16 };

/* The steps of the key grid (G steps over the clip) where some channel has a key: 0 always, a
 * one-shot's end G too (local_rate.c's key_steps). */
static uint32_t key_steps(const cb_animation *a, const cb_palette_clip *clip, double key_fps, uint32_t G, uint32_t *out)
{
    bool *on = calloc((size_t)G + 1, sizeof *on);
    uint32_t n = 0;
    on[0] = true, on[G] = !clip->loops;
    for (uint32_t c = 0; c < a->channel_count; ++c) {
        const cb_channel *ch = &a->channels[c];
        for (uint32_t k = 0; k < ch->key_count; ++k) {
            double g = round((ch->times[k] - clip->start) * key_fps);
            if (g >= 0 && g < G) on[(uint32_t)g] = true;
        }
    }
    for (uint32_t g = 0; g <= G; ++g)
        if (on[g]) out[n++] = g;
    free(on);
    return n;
}

typedef struct scratch {
    cb_sampler *s;
    const cb_model *m;
    const cb_palette *p;
    uint32_t bones;
    double *mats, *exact, *a, *b;
} scratch;

/* Worst vertex distance between the skin under the palette's rows r0, r1 blended at f and exact
 * skinning at time t. */
static double blend_error(scratch *w, int32_t anim, uint32_t r0, uint32_t r1, double f, double t)
{
    for (uint32_t j = 0; j < w->bones; ++j) cb_palette_blend(w->p, w->p->texels, r0, r1, f, j, w->mats + 16 * j);
    cb_sample_joint_matrices(w->s, anim, t, w->exact);
    bench_errors e = {0};
    bench_skin_errors(w->m, 0, w->mats, w->exact, w->a, w->b, &e);
    return e.worst;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_timed_global MODEL.glb [MAX_ERROR_MM_PER_M]\n");
        return 2;
    }
    bench_model model = bench_load("bench_timed_global", argv[1]);
    double max_error_mm = argc > 2 ? atof(argv[2]) : 1;
    uint32_t total_rows = 0, total_map = 0;
    bool all_met = true;
    for (uint32_t an = 0; an < model.m->animation_count; ++an) {
        const cb_animation *anim = &model.m->animations[an];
        cb_error err = {0};
        cb_clip_info info;
        if (cb_clip_analyze(model.s, (int32_t)an, 30, -1, NULL, &info, &err)) return fprintf(stderr, "%s\n", err.message), 1;
        double key_fps = cb_key_grid_fps(anim, info.t0, info.duration, CB_FPS_LIMIT);
        uint32_t M = MOST_SPLITS;
        while (M > 1 && key_fps * M > CB_FPS_LIMIT) M /= 2;
        cb_bake_options o = cb_default_bake_options();
        o.layout = CB_LAYOUT_QPOS, o.precision = CB_PRECISION_U16, o.fps = key_fps * M;
        o.root_motion = CB_ROOT_MOTION_KEEP, o.measure_all = true, o.threads = 1;
        cb_clip_plan plan = {.animation = (int32_t)an, .loop = info.loops ? 1 : 0};
        cb_palette p;
        if (cb_palette_bake(model.s, &o, &plan, 1, &p, &err)) return fprintf(stderr, "%s\n", err.message), 1;
        const cb_palette_clip *pc = &p.clips[0];
        cb_sampler_set_baked_loop(model.s, (int32_t)an, pc->loops, pc->start, pc->duration);
        uint32_t G = cb_clip_step_count(pc->duration, key_fps), cells = pc->loops ? pc->frames : pc->frames - 1;
        if (cells != G * M) {
            fprintf(stderr, "%s: %s framed at %u cells, not %u x %u\n", model.name, anim->name, cells, G, M);
            cb_palette_free(&p);
            continue;
        }
        scratch w = {.s = model.s, .m = model.m, .p = &p, .bones = p.bone_count};
        w.mats = malloc(16 * sizeof(double) * w.bones), w.exact = malloc(16 * sizeof(double) * w.bones);
        w.a = malloc(3 * sizeof(double) * model.vertices), w.b = malloc(3 * sizeof(double) * model.vertices);
        uint32_t *keys = malloc(((size_t)G + 1) * sizeof *keys), count = key_steps(anim, pc, key_fps, G, keys);
        uint32_t n = pc->loops ? count : count - 1, rows = pc->loops ? 0 : 1, largest = 1, misses = 0;
        double goal = max_error_mm / 1000 * p.model_height, worst = 0, dt = pc->duration / cells;
        /* the encoding at every candidate row: the rows kept are some of them */
        double *enc = malloc(((size_t)p.rows) * sizeof *enc);
        for (uint32_t r = 0; r < p.rows; ++r) enc[r] = blend_error(&w, (int32_t)an, r, r, 0, pc->start + r * dt);
        for (uint32_t i = 0; i < n; ++i) {
            uint32_t from = keys[i] * M, to = (i + 1 < count ? keys[i + 1] : G) * M, s = 1;
            double e = INFINITY;
            for (; s <= M; s *= 2) {
                if ((to - from) % s) continue;
                uint32_t d = (to - from) / s;
                e = 0;
                for (uint32_t j = 0; j < s && e <= goal; ++j) {
                    uint32_t c0 = from + j * d, c1 = c0 + d, r1 = c1 == cells && pc->loops ? 0 : c1;
                    e = fmax(e, fmax(enc[c0], enc[r1]));
                    e = fmax(e, blend_error(&w, (int32_t)an, c0, r1, 0.5, pc->start + (c0 + 0.5 * d) * dt));
                }
                if (e <= goal) break;
            }
            if (s > M) s = M, ++misses;
            worst = fmax(worst, e);
            rows += s, largest = s > largest ? s : largest;
        }
        uint32_t map_rows = cb_timed_map_rows(G * largest, p.row_texels);
        total_rows += rows, total_map += map_rows, all_met = all_met && !misses;
        printf("{\"model\": \"%s\", \"clip\": \"%s\", \"loops\": %s, \"key_fps\": %g, \"key_intervals\": %u, "
               "\"rows_on_keys\": %u, \"map_rows\": %u, \"cells\": %u, \"cell_rate\": %g, \"largest_split\": %u, "
               "\"error_mm_per_m\": %.4f, \"intervals_over_budget\": %u}\n",
               model.name, anim->name, pc->loops ? "true" : "false", key_fps, n, rows, map_rows, G * largest,
               key_fps * largest, largest, worst / p.model_height * 1000, misses);
        free(enc), free(keys), free(w.mats), free(w.exact), free(w.a), free(w.b);
        cb_palette_free(&p);
    }
    printf("{\"model\": \"%s\", \"rows_on_keys\": %u, \"map_rows\": %u, \"all_met\": %s}\n", model.name, total_rows,
           total_map, all_met ? "true" : "false");
    bench_free(&model);
    return 0;
}
