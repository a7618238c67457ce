/* reference_soles.h - a quadruped's feet measured independently of crowdbake's pose code: joint
 * matrices (the reference's fps30.csv files of ../shared/reference, sampled by another
 * implementation and read by ref_read_clip; or a baked .pal's rows through the one-header C
 * reader) skinning the mesh's own sole vertices. A sole is the vertices in the lowest
 * 3% of the height of Idle's first pose, split into four by which side and end of the body they
 * stand at; a foot is tracked by its sole's mean position. Used by test_feet.c, test_plant_feet.c
 * and test_row_travel.c; test_sockets_contacts.c reads the reference through ref_read_clip.
 * Include after testutil.h. */
#ifndef CB_REFERENCE_SOLES_H
#define CB_REFERENCE_SOLES_H

#include <math.h>

enum { REF_MAX_FRAMES = 160, REF_MAX_BONES = 64, REF_SOLE_MAX = 1024 };

/* All joints' reference matrices over one clip's frames (t from the clip's start). */
typedef struct ref_clip {
    uint32_t frames, bones;
    double t[REF_MAX_FRAMES];
    double (*m)[REF_MAX_BONES][16];
} ref_clip;

static inline void ref_read_clip(const char *csv, const char *clip, ref_clip *out)
{
    FILE *f = fopen(csv, "r");
    assert_non_null(f);
    char line[4096], quoted[160];
    snprintf(quoted, sizeof quoted, ",\"%.140s\",", clip);
    out->frames = out->bones = 0;
    double t0 = 0;
    while (fgets(line, sizeof line, f)) {
        char *at = strstr(line, quoted);
        if (line[0] == '#' || !at) continue;
        unsigned frame, frames, skin, j;
        double time, m[16];
        if (sscanf(at + strlen(quoted), "%u,%u,%lf,%u,%u,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &frame,
                   &frames, &time, &skin, &j, &m[0], &m[1], &m[2], &m[3], &m[4], &m[5], &m[6], &m[7], &m[8], &m[9], &m[10], &m[11],
                   &m[12], &m[13], &m[14], &m[15]) != 21 || frame >= REF_MAX_FRAMES || j >= REF_MAX_BONES)
            continue;
        if (frame == 0 && j == 0) t0 = time;
        out->t[frame] = time - t0;
        memcpy(out->m[frame][j], m, sizeof m);
        if (frame + 1 > out->frames) out->frames = frame + 1;
        if (j + 1 > out->bones) out->bones = j + 1;
    }
    fclose(f);
}

/* One sole: its vertices, as primitive and index. */
typedef struct ref_sole {
    uint32_t count;
    uint32_t prim[REF_SOLE_MAX], vertex[REF_SOLE_MAX];
} ref_sole;

static inline void ref_skin_vertex(const cb_primitive *p, uint32_t v, const double (*mats)[16], double out[3])
{
    const float *x = p->positions + (size_t)v * 3;
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i < 4; ++i) {
        double w = p->weights[(size_t)v * 4 + i];
        const double *m = mats[p->joints[(size_t)v * 4 + i]];
        for (int k = 0; k < 3; ++k) out[k] += w * (m[k] * x[0] + m[4 + k] * x[1] + m[8 + k] * x[2] + m[12 + k]);
    }
}

/* The four soles of a pose (Idle's first), and the model's height there. */
static inline double ref_find_soles(const cb_model *m, const double (*pose)[16], ref_sole feet[4])
{
    double lo = INFINITY, hi = -INFINITY, p[3], cx = 0, cz = 0;
    uint32_t n = 0;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi)
        for (uint32_t v = 0; v < m->primitives[pi].vertex_count; ++v)
            ref_skin_vertex(&m->primitives[pi], v, pose, p), lo = fmin(lo, p[1]), hi = fmax(hi, p[1]);
    double height = hi - lo;
    memset(feet, 0, 4 * sizeof *feet);
    for (int pass = 0; pass < 2; ++pass)
        for (uint32_t pi = 0; pi < m->primitive_count; ++pi)
            for (uint32_t v = 0; v < m->primitives[pi].vertex_count; ++v) {
                ref_skin_vertex(&m->primitives[pi], v, pose, p);
                if (p[1] > lo + 0.03 * height) continue;
                if (pass == 0) {
                    cx += p[0], cz += p[2], ++n;
                    continue;
                }
                ref_sole *f = &feet[(p[0] > cx / n) * 2 + (p[2] > cz / n)];
                if (f->count < REF_SOLE_MAX) f->prim[f->count] = pi, f->vertex[f->count++] = v;
            }
    return height;
}

/* A sole's mean position at one frame. */
static inline void ref_sole_at(const cb_model *m, const ref_sole *f, const double (*mats)[16], double out[3])
{
    double p[3];
    out[0] = out[1] = out[2] = 0;
    for (uint32_t i = 0; i < f->count; ++i) {
        ref_skin_vertex(&m->primitives[f->prim[i]], f->vertex[i], mats, p);
        for (int k = 0; k < 3; ++k) out[k] += p[k] / f->count;
    }
}

#endif
