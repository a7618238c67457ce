/* bench_local_rate.c - each clip's rate for local rows (src/core/local_rate.c, issue 43 item 1)
 * and what it costs: a JSON line per clip (its key rate, the rate chosen, its error in float64,
 * the rates measured, its rows against --fps 30's), then one for the model (rows against a
 * global --fps 30 bake's: the bytes' ratio, as a local u16 row takes what a global qpos u16 row
 * takes, the bone range table aside). Run it under callgrind for the choice's instructions alone:
 *
 *   bench_local_rate MODEL [MAX_ERROR_MM_PER_M [MAX_FPS]]   (defaults 1 and 120, the bake's) */
#include "bench_model.h"

#include "core/local_rate.h"

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_local_rate MODEL.glb [MAX_ERROR_MM_PER_M [MAX_FPS]]\n");
        return 2;
    }
    bench_model model = bench_load("bench_local_rate", argv[1]);
    double max_error_mm = argc > 2 ? atof(argv[2]) : 1, max_fps = argc > 3 ? atof(argv[3]) : CB_AUTO_MAX_FPS;
    cb_error err = {0};
    palette_skin_facts facts;
    local_skeleton skeleton;
    if (palette_skin_facts_build(model.s, &facts, &err) || !local_skeleton_build(model.m, 0, &skeleton)) {
        fprintf(stderr, "bench_local_rate: %s\n", err.message[0] ? err.message : "out of memory");
        return 1;
    }
    uint64_t rows = 0, rows30 = 0;
    double worst_mm = 0;
    uint32_t probes = 0;
    for (uint32_t a = 0; a < model.m->animation_count; ++a) {
        cb_clip_info info;
        local_rate r;
        if (cb_clip_analyze(model.s, (int32_t)a, 30, -1, NULL, &info, &err) ||
            local_clip_rate(model.s, &facts, &skeleton, &info, CB_ROOT_MOTION_KEEP, NULL, max_error_mm / 1000 * facts.height, max_fps, &r, &err)) {
            fprintf(stderr, "bench_local_rate: %s\n", err.message);
            return 1;
        }
        uint32_t mine = cb_clip_step_count(info.duration, r.fps) + !info.loops, at30 = info.frames;
        rows += mine, rows30 += at30, probes += r.probes;
        worst_mm = r.error_mm > worst_mm ? r.error_mm : worst_mm;
        printf("{\"model\": \"%s\", \"clip\": \"%s\", \"key_fps\": %g, \"fps\": %g, \"met\": %s, \"error_mm_per_m\": %.4f, "
               "\"probes\": %u, \"rows\": %u, \"rows_30fps\": %u}\n",
               model.name, model.m->animations[a].name, r.key_fps, r.fps, r.met ? "true" : "false", r.error_mm, r.probes, mine,
               at30);
    }
    printf("{\"model\": \"%s\", \"bones\": %u, \"rows\": %llu, \"rows_30fps\": %llu, \"rows_ratio\": %.3f, "
           "\"worst_error_mm_per_m\": %.4f, \"probes\": %u}\n",
           model.name, skeleton.bones, (unsigned long long)rows, (unsigned long long)rows30,
           rows30 ? (double)rows / (double)rows30 : 0, worst_mm, probes);
    local_skeleton_free(&skeleton);
    palette_skin_facts_free(&facts);
    bench_free(&model);
    return 0;
}
