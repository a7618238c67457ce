/* bench_gl_mesh.c - see bench_gl_mesh.h. */
#include "bench_gl_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void bench_sort_influences(int32_t *joints, float *weights, uint32_t vertices)
{
    for (uint32_t v = 0; v < vertices; ++v) { /* insertion sort of four, descending */
        int32_t *j = joints + v * 4;
        float *w = weights + v * 4;
        for (int a = 1; a < 4; ++a)
            for (int b = a; b > 0 && w[b] > w[b - 1]; --b) {
                float tw = w[b];
                int32_t tj = j[b];
                w[b] = w[b - 1], j[b] = j[b - 1], w[b - 1] = tw, j[b - 1] = tj;
            }
    }
}

static int influence_count(const float *weights, uint32_t v)
{
    const float *w = weights + v * 4;
    return w[3] != 0 ? 4 : w[2] != 0 ? 3 : w[1] != 0 ? 2 : 1;
}

void bench_sort_triangles(uint32_t *indices, uint32_t index_count, const float *weights)
{
    uint32_t triangles = index_count / 3, at = 0;
    uint32_t *out = malloc((size_t)index_count * sizeof *out);
    if (!out) return; /* the order is an optimisation: the mesh stays as it was */
    for (int count = 1; count <= 4; ++count) /* a counting sort by the triangle's largest count: stable */
        for (uint32_t t = 0; t < triangles; ++t) {
            const uint32_t *tri = indices + t * 3;
            int c = influence_count(weights, tri[0]);
            for (int k = 1; k < 3; ++k) c = influence_count(weights, tri[k]) > c ? influence_count(weights, tri[k]) : c;
            if (c == count) memcpy(out + at, tri, 3 * sizeof *tri), at += 3;
        }
    memcpy(indices, out, (size_t)at * sizeof *out);
    free(out);
}

/* The largest distance (model units) between a vertex skinned with all its influences and with its `keep` largest
 * (weights renormalized) at one pose; joints and weights sorted largest first. */
static double worst_tier_error(const double *mats, const float *positions, const int32_t *joints, const float *weights,
                               uint32_t vertices, int keep)
{
    double worst = 0;
    for (uint32_t v = 0; v < vertices; ++v) {
        double full[3] = {0}, part[3] = {0}, sum = 0;
        for (int i = 0; i < 4 && weights[v * 4 + i] != 0; ++i) {
            const double *m = mats + (size_t)joints[v * 4 + i] * 16, w = weights[v * 4 + i];
            const float *x = positions + (size_t)v * 3;
            for (int r = 0; r < 3; ++r) {
                double p = m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r];
                full[r] += w * p;
                if (i < keep) part[r] += w * p;
            }
            if (i < keep) sum += w;
        }
        double d2 = 0;
        for (int r = 0; r < 3; ++r) d2 += (part[r] / sum - full[r]) * (part[r] / sum - full[r]);
        if (sum > 0 && sqrt(d2) > worst) worst = sqrt(d2);
    }
    return worst;
}

void bench_lod_thresholds(cb_sampler *sampler, const cb_palette *pal, const float *positions, const int32_t *joints,
                          const float *weights, uint32_t vertices, double size, double pixel_error, int poses, float out[2])
{
    const cb_model *model = cb_sampler_model(sampler);
    double *mats = malloc((size_t)pal->bone_count * 16 * sizeof(double)), worst[2] = {0, 0};
    for (int k = 0; k < poses; ++k) {
        uint32_t row = (uint32_t)((k + 0.5) * pal->rows / poses), c = 0; /* the k-th of `poses` rows over every clip */
        while (c + 1 < pal->clip_count && row >= pal->clips[c].frames) row -= pal->clips[c++].frames;
        int32_t animation = -1;
        for (uint32_t a = 0; a < model->animation_count; ++a)
            if (!strcmp(model->animations[a].name, pal->clips[c].name)) animation = (int32_t)a;
        cb_sample_joint_matrices(sampler, animation, pal->clips[c].start + row / pal->clips[c].fps, mats);
        for (int t = 0; t < 2; ++t) worst[t] = fmax(worst[t], worst_tier_error(mats, positions, joints, weights, vertices, t + 1));
    }
    free(mats);
    for (int t = 0; t < 2; ++t) out[t] = worst[t] > pixel_error * size / 1e6 ? (float)(pixel_error * size / worst[t]) : 1e6f;
    out[1] = fmaxf(out[1], out[0]); /* two: never under one */
}

char *bench_read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = calloc((size_t)n + 1, 1);
    if (fread(text, 1, (size_t)n, f) != (size_t)n) { fclose(f); free(text); return NULL; }
    fclose(f);
    return text;
}

/* Share of the pixels covered in either image whose colours differ by more than 8 of 255. */
double bench_image_difference(const unsigned char *a, const unsigned char *b, int width, int height, long *covered)
{
    long differ = 0;
    *covered = 0;
    for (size_t i = 0; i < (size_t)width * height * 4; i += 4) {
        bool ca = a[i] | a[i + 1] | a[i + 2], cb = b[i] | b[i + 1] | b[i + 2];
        if (!ca && !cb) continue;
        ++*covered;
        for (int k = 0; k < 3; ++k)
            if (abs(a[i + k] - b[i + k]) > 8) { ++differ; break; }
    }
    return *covered ? (double)differ / *covered : 1;
}

void bench_herd_view(double side, double a, float view_projection[16])
{
    double f = 1 / tan(25 * acos(-1.0) / 180), near = side * 0.01, far = side * 10;
    double eye[3] = {0, side * 0.8, side * 0.7}, len = sqrt(eye[1] * eye[1] + eye[2] * eye[2]);
    double zc[3] = {0, eye[1] / len, eye[2] / len}, xc[3] = {1, 0, 0}, yc[3] = {0, zc[2], -zc[1]};
    double view[16] = {xc[0], yc[0], zc[0], 0, xc[1], yc[1], zc[1], 0, xc[2], yc[2], zc[2], 0,
                       0, -(yc[1] * eye[1] + yc[2] * eye[2]), -(zc[1] * eye[1] + zc[2] * eye[2]), 1};
    double proj[16] = {f / a, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double sum = 0;
            for (int k = 0; k < 4; ++k) sum += proj[k * 4 + r] * view[c * 4 + k];
            view_projection[c * 4 + r] = (float)sum;
        }
}
