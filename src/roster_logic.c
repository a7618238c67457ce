/* roster.c - roster logic on plain structs: see catalog.h. */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/catalog.h"

void cb_catalog_free(cb_catalog *c)
{
    if (!c) return;
    cb_arena_free(c->arena);
    memset(c, 0, sizeof *c);
}

static bool contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    if (n == 0) return false;
    for (; *hay; ++hay) {
        size_t i = 0;
        while (i < n && hay[i] && tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i])) ++i;
        if (i == n) return true;
    }
    return false;
}

int cb_match_state(const char *const *clips, uint32_t clip_count, const char *const *keywords, uint32_t keyword_count)
{
    for (uint32_t k = 0; k < keyword_count; ++k)
        for (uint32_t c = 0; c < clip_count; ++c)
            if (contains_nocase(clips[c], keywords[k])) return (int)c;
    return -1;
}

/* ---- ground speed ---- */

static bool is_leaf(const cb_model *m, const cb_skin *skin, uint32_t j)
{
    for (uint32_t k = 0; k < skin->joint_count; ++k)
        for (int32_t p = m->nodes[skin->joints[k]].parent; p >= 0; p = m->nodes[p].parent)
            if (p == skin->joints[j]) return false;
    return true;
}

/* Mean horizontal speed, relative to the root, of one foot while it is down (in the lowest
 * tenth of its height range): a planted foot slides back at the ground speed. h, x, z: the
 * foot's height and horizontal offset from the root at `samples` times dt apart. */
static double stance_speed(const double *h, const double *x, const double *z, uint32_t samples, double dt, double size)
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < samples; ++i) lo = fmin(lo, h[i]), hi = fmax(hi, h[i]);
    /* A foot that never lifts is not stepping: its sway is not travel. */
    if (hi - lo < 0.02 * size) return 0;
    double band = lo + 0.1 * (hi - lo), dist = 0, time = 0;
    for (uint32_t i = 0; i + 1 < samples; ++i)
        if (h[i] <= band && h[i + 1] <= band) {
            dist += hypot(x[i + 1] - x[i], z[i + 1] - z[i]);
            time += dt;
        }
    return time > 0 && hi > lo ? dist / time : 0;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

enum { STANCE_SAMPLES = 240, MAX_FEET = 64 };

/* Mean stance speed of the feet (leaf joints in the lowest 15 % of the rest pose), their
 * median; 0 when no foot steps or they only shuffle on the spot. Each pose is sampled once
 * for every foot (a pose per foot and time would repeat the same work for each foot). */
static double feet_speed(cb_sampler *s, const cb_clip_info *clip, double lo, double size)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_skin *skin = &m->skins[cb_sampler_skin(s)];
    const double *g = cb_sample_globals(s, -1, 0);
    uint32_t root = cb_skin_root_joint(m, cb_sampler_skin(s)), feet = 0, candidates[MAX_FEET], n = 0;
    for (uint32_t j = 0; j < skin->joint_count && n < MAX_FEET; ++j) {
        double y = g[(size_t)skin->joints[j] * 16 + 13];
        if (y <= lo + 0.15 * size && is_leaf(m, skin, j)) candidates[n++] = j;
    }
    if (n == 0) return 0;
    double *track = malloc((size_t)n * 3 * STANCE_SAMPLES * sizeof(double)); /* per foot: h, x, z */
    if (!track) return 0;
    double dt = clip->duration / STANCE_SAMPLES;
    for (uint32_t i = 0; i < STANCE_SAMPLES; ++i) {
        g = cb_sample_globals(s, clip->animation, clip->t0 + i * dt);
        const double *r = g + (size_t)skin->joints[root] * 16;
        for (uint32_t k = 0; k < n; ++k) {
            const double *f = g + (size_t)skin->joints[candidates[k]] * 16;
            double *h = track + (size_t)k * 3 * STANCE_SAMPLES;
            h[i] = f[13], h[STANCE_SAMPLES + i] = f[12] - r[12], h[2 * STANCE_SAMPLES + i] = f[14] - r[14];
        }
    }
    double speeds[MAX_FEET];
    for (uint32_t k = 0; k < n; ++k) {
        const double *h = track + (size_t)k * 3 * STANCE_SAMPLES;
        double v = stance_speed(h, h + STANCE_SAMPLES, h + 2 * STANCE_SAMPLES, STANCE_SAMPLES, dt, size);
        if (v > 0) speeds[feet++] = v;
    }
    free(track);
    if (feet == 0) return 0;
    qsort(speeds, feet, sizeof speeds[0], compare_double);
    return speeds[feet / 2] > 0.1 * size ? speeds[feet / 2] : 0; /* shuffling on the spot is not travel */
}

void cb_measure_ground_speed(cb_sampler *s, const cb_clip_info *clip, cb_ground_speed *out)
{
    memset(out, 0, sizeof *out);
    out->method = "none";
    if (clip->duration <= 0) return;
    const cb_model *m = cb_sampler_model(s);
    const cb_skin *skin = &m->skins[cb_sampler_skin(s)];
    const double *g = cb_sample_globals(s, -1, 0);
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        double y = g[(size_t)skin->joints[j] * 16 + 13];
        lo = fmin(lo, y), hi = fmax(hi, y);
    }
    double size = hi - lo > 0 ? hi - lo : 1;
    out->root = clip->ground_speed;
    out->feet = feet_speed(s, clip, lo, size);
    /* Root travel counts when it is more than a percent of the skeleton per second. A planted
     * foot is still in the world, so relative to the root it slides back at the ground speed
     * whether the root moves or not: where both exist they agree, and a root that moves far
     * less than the feet only drifts while the clip walks in place. */
    bool root_moves = out->root > 0.01 * size;
    if (out->feet > 0 && (!root_moves || out->root < 0.5 * out->feet)) {
        out->speed = out->feet;
        out->method = root_moves ? "planted feet (the root only drifts)" : "planted feet";
    } else if (root_moves) {
        out->speed = out->root;
        out->method = "root motion";
    }
}

/* ---- LODs ---- */

cb_status cb_lod_remap(const cb_model *main, int32_t main_skin, const cb_model *lod, int32_t lod_skin, uint32_t *remap,
                       cb_error *err)
{
    const cb_skin *a = &main->skins[main_skin], *b = &lod->skins[lod_skin];
    for (uint32_t i = 0; i < b->joint_count; ++i) {
        const char *name = lod->nodes[b->joints[i]].name;
        uint32_t k = 0;
        while (k < a->joint_count && strcmp(main->nodes[a->joints[k]].name, name) != 0) ++k;
        if (k == a->joint_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: LOD joint '%s' is not a joint of %s; a LOD must use the same rig", lod->source,
                           name, main->source);
        const double *x = a->inverse_bind + (size_t)k * 16, *y = b->inverse_bind + (size_t)i * 16;
        double scale = 1;
        for (int e = 0; e < 16; ++e) scale = fmax(scale, fabs(x[e]));
        for (int e = 0; e < 16; ++e)
            if (fabs(x[e] - y[e]) > 1e-4 * scale)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: LOD joint '%s' has another bind pose than in %s (inverse bind matrix element %d: %g vs "
                               "%g); re-export the LOD from the same rig",
                               lod->source, name, main->source, e, y[e], x[e]);
        remap[i] = k;
    }
    return CB_OK;
}
