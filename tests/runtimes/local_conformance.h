/* local_conformance.h - the local conformance cases (conformance.h's local_qpos_u16, local_qpos_float,
 * local_blocks: .pal version 6) as a runtime's test compares them. Steady instances against the C
 * runtime's expected positions (which compose); each clip and time's cross-fading instance
 * (conf_instance's last) against the spec's cross-fade, the two clips' local rows blended before
 * composing (local_reference.h), because conf_expected mixes the two composed skins, which is right
 * for global rows only. Header-only, like testutil.h. */
#ifndef CB_LOCAL_CONFORMANCE_H
#define CB_LOCAL_CONFORMANCE_H

#include "runtimes/conformance.h"
#include "runtimes/local_reference.h"

/* The spec's positions of a fading instance of a local case: both clips' local rows blended, then
 * composed (local_reference.h); 3 doubles a vertex. */
static inline void local_fade_expected(const conf_palette *p, const float v[16], double time, double *out)
{
    cb_palette view = p->view;
    view.texels = (void *)p->pal.texels;
    cb_instance in = {v[4], v[5], v[6], v[7]}, from = {v[8], v[9], v[10], v[11]};
    double fade = fmin(fmax((time - v[12]) / v[13], 0), 1);
    double *mats = malloc(view.bone_count * 16 * sizeof(double));
    local_matrices(&view, &in, &from, fade, time, mats);
    cb_skin_positions(&p->model->primitives[0], mats, out);
    free(mats);
}

/* What a runtime skinned for a local case (`got`, conf_positions(c, k) positions): [0] the worst
 * error of its steady instances against the C runtime's expected positions, [1] of its fading ones
 * against local_fade_expected, [2] of its fading ones against conf_expected's mixed skins (reported
 * only: the spec does not mix skins), in tolerances. */
static inline void local_conformance_ratios(const conformance *c, const conf_case *k, const float *got, double ratio[3])
{
    const conf_palette *p = &c->palettes[k->palette];
    size_t verts = p->model->primitives[0].vertex_count, at = 0, size = 0;
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s.expected", c->dir, k->name);
    float *want = (float *)read_whole_file(path, &size);
    assert_int_equal(size, conf_positions(c, k) * 12);
    double *fading = malloc(verts * 3 * sizeof(double)), tol = 1e-5 * fmax(1.0, p->view.model_height);
    ratio[0] = ratio[1] = ratio[2] = 0;
    for (int t = 0; t < CONF_TIMES; ++t)
        for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
            for (int i = 0; i < CONF_PER_CLIP; ++i, at += verts * 3) {
                bool fades = i == CONF_PER_CLIP - 1;
                float v[16];
                conf_instance(&p->view.clips[cl], conf_times[t], i, 0, v);
                if (fades) local_fade_expected(p, v, conf_times[t], fading);
                for (size_t j = 0; j < verts * 3; ++j) {
                    ratio[fades] = fmax(ratio[fades], fabs((fades ? fading[j] : want[at + j]) - got[at + j]) / tol);
                    if (fades) ratio[2] = fmax(ratio[2], fabs(want[at + j] - got[at + j]) / tol);
                }
            }
    free(want), free(fading);
}

#endif
