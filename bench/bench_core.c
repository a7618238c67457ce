/* bench_core.c MODEL.glb PALETTE.pal [EXR] - in-process timings that the command line cannot
 * show: pure joint-matrix sampling throughput (what the peer measures), and opening a .pal
 * through the reader header (without and with checksum verification) against reading the
 * same palette's EXR through OpenEXR. Prints one JSON object. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "crowdbake_pal.h"
#include "crowdbake/exr.h"
#include "crowdbake/gltf.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Samples every frame of every clip (30 fps, crowdbake's framing) on one thread, as 4x4
 * matrices or, for similarity rigs, as the similarities the qpos bake samples. */
static double sample_all(cb_model *m, bool similarities, uint64_t *matrices)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    uint32_t joints = m->skins[0].joint_count;
    double *mats = malloc((size_t)joints * 16 * sizeof(double));
    cb_similarity *sims = malloc((size_t)joints * CB_SAMPLE_BATCH * sizeof *sims);
    *matrices = 0;
    double t0 = now();
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err);
        for (uint32_t f = 0; similarities && f < info.frames; f += CB_SAMPLE_BATCH) {
            uint32_t frames[CB_SAMPLE_BATCH], count = 0;
            while (count < CB_SAMPLE_BATCH && f + count < info.frames) frames[count] = f + count, ++count;
            cb_clip_frame_similarities(s, &info, frames, count, CB_ROOT_MOTION_KEEP, sims);
        }
        for (uint32_t f = 0; !similarities && f < info.frames; ++f)
            cb_clip_frame_matrices(s, &info, f, CB_ROOT_MOTION_KEEP, mats);
        *matrices += (uint64_t)info.frames * joints;
    }
    double t = now() - t0;
    free(mats);
    free(sims);
    cb_sampler_free(s);
    return t;
}

static double median(double *v, int n)
{
    for (int i = 1; i < n; ++i)
        for (int k = i; k > 0 && v[k] < v[k - 1]; --k) { double t = v[k]; v[k] = v[k - 1]; v[k - 1] = t; }
    return v[n / 2];
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_core MODEL PALETTE.pal [PALETTE.exr]\n");
        return 2;
    }
    cb_error err = {0};
    cb_model *m = cb_gltf_load(argv[1], NULL, &err);
    if (!m) return fprintf(stderr, "%s\n", err.message), 1;
    uint64_t matrices = 0;
    double runs[7];
    for (int i = 0; i < 7; ++i) runs[i] = sample_all(m, false, &matrices);
    double sample_s = median(runs, 7), similarity_s = 0;
    cb_sampler *probe = cb_sampler_create(m, 0, &err);
    bool similar = probe && cb_sampler_is_similarity(probe);
    cb_sampler_free(probe);
    if (similar) {
        for (int i = 0; i < 7; ++i) runs[i] = sample_all(m, true, &matrices);
        similarity_s = median(runs, 7);
    }

    char msg[256];
    cbpal_file f;
    double open_us[101];
    for (int i = 0; i < 101; ++i) {
        double t0 = now();
        if (cbpal_open(argv[2], 0, &f, msg, sizeof msg)) return fprintf(stderr, "%s\n", msg), 1;
        open_us[i] = (now() - t0) * 1e6;
        cbpal_close(&f);
    }
    double verify_s[7];
    size_t size = 0;
    for (int i = 0; i < 7; ++i) {
        double t0 = now();
        if (cbpal_open(argv[2], CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg)) return fprintf(stderr, "%s\n", msg), 1;
        verify_s[i] = now() - t0;
        size = f.size;
        cbpal_close(&f);
    }
    printf("{\"model\": \"%s\", \"sample_seconds\": %.6f, \"matrices\": %llu, \"matrices_per_second\": %.0f, "
           "\"pal_bytes\": %zu, \"pal_open_us\": %.2f, \"pal_verify_gb_per_s\": %.2f",
           argv[1], sample_s, (unsigned long long)matrices, matrices / sample_s, size, median(open_us, 101),
           size / median(verify_s, 7) / 1e9);
    if (similar) printf(", \"similarity_matrices_per_second\": %.0f", matrices / similarity_s);
    if (argc > 3) {
        double exr_s[5];
        for (int i = 0; i < 5; ++i) {
            cb_exr_image img;
            double t0 = now();
            if (cb_exr_read(argv[3], &img, &err)) return fprintf(stderr, "%s\n", err.message), 1;
            exr_s[i] = now() - t0;
            cb_exr_image_free(&img);
        }
        printf(", \"exr_read_us\": %.1f", median(exr_s, 5) * 1e6);
    }
    printf("}\n");
    cb_model_free(m);
    return 0;
}
