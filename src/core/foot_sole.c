/* foot_sole.c - a rig's feet as soles of skinned vertices (foot_sole.h). */
#include "foot_sole.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"       /* CB_TARGET_CLONES */
#include "palette_bake.h" /* palette_bind_positions */
#include "sampler.h"      /* cb_joint_subset, CB_SAMPLE_BATCH */

/* A sole vertex lies in the lowest 3% of the model's height in the rest pose; vertices within 8%
 * of the height of each other (side by side) stand on one foot: a human's feet stand 14% apart,
 * a quadruped's 17-27%, while a paw's sole spans a few percent. */
#define SOLE_BAND 0.03
#define SOLE_LINK 0.08
enum { CB_MAX_FEET_CAP = 16 };

static bool word_at(const char *name, size_t i, const char *word)
{
    for (size_t k = 0; word[k]; ++k)
        if (tolower((unsigned char)name[i + k]) != word[k]) return false;
    return true;
}

bool rig_name_is_control(const char *name)
{
    size_t n = strlen(name);
    for (size_t i = 0; i < n; ++i) {
        if (word_at(name, i, "pole") || word_at(name, i, "target") || word_at(name, i, "ctrl")) return true;
        /* "IK" as a word of its own: not inside "Pike" or "kick" (a letter before it that is
         * lower case, or a lower-case letter after it, makes it part of another word). */
        if (i + 2 <= n && word_at(name, i, "ik")) {
            bool before = i > 0 && islower((unsigned char)name[i - 1]);
            bool after = i + 2 < n && islower((unsigned char)name[i + 2]);
            bool upper = name[i] == 'I' && name[i + 1] == 'K';
            if (!before && !after && (upper || i == 0 || !isalpha((unsigned char)name[i - 1]))) return true;
        }
    }
    return false;
}

void rig_deforming_joints(const cb_model *m, int32_t skin, bool *out)
{
    memset(out, 0, m->skins[skin].joint_count * sizeof *out);
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin || !prim->weights) continue;
        for (size_t i = 0; i < (size_t)prim->vertex_count * 4; ++i)
            if (prim->weights[i] > 0 && prim->joints[i] < m->skins[skin].joint_count) out[prim->joints[i]] = true;
    }
}

static bool is_ancestor(const cb_model *m, int32_t node, int32_t of)
{
    for (int32_t p = m->nodes[of].parent; p >= 0; p = m->nodes[p].parent)
        if (p == node) return true;
    return false;
}

/* Whether two joints are one leg: one above the other. */
static bool same_leg(const cb_model *m, int32_t skin, uint32_t a, uint32_t b)
{
    int32_t x = m->skins[skin].joints[a], y = m->skins[skin].joints[b];
    return is_ancestor(m, x, y) || is_ancestor(m, y, x);
}

static uint32_t dominant_joint(const sole_vertex *v)
{
    int best = 0;
    for (int k = 1; k < 4; ++k)
        if (v->weight[k] > v->weight[best]) best = k;
    return v->joint[best];
}

/* The sole vertices of the rest pose: every skinned vertex in the lowest SOLE_BAND of the height. */
static sole_vertex *collect_sole_vertices(cb_sampler *s, const double *rest, double lo, double size, size_t *count)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    size_t n = 0, cap = 0;
    sole_vertex *out = NULL;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        double *pos = malloc((size_t)prim->vertex_count * 3 * sizeof(double));
        if (!pos) break;
        cb_skin_positions(prim, rest, pos);
        for (uint32_t v = 0; v < prim->vertex_count; ++v) {
            if (pos[(size_t)v * 3 + 1] > lo + SOLE_BAND * size) continue;
            if (n == cap) {
                sole_vertex *grown = realloc(out, (cap = cap ? cap * 2 : 64) * sizeof *out);
                if (!grown) break;
                out = grown;
            }
            sole_vertex *sv = &out[n++];
            for (int k = 0; k < 3; ++k) sv->p[k] = prim->positions[(size_t)v * 3 + k];
            for (int k = 0; k < 4; ++k)
                sv->joint[k] = prim->joints[(size_t)v * 4 + k], sv->weight[k] = prim->weights[(size_t)v * 4 + k];
        }
        free(pos);
    }
    *count = n;
    return out;
}

/* The joint a foot is named after: the one carrying most of its vertices' weight, among the
 * joints that deform and are not rig controls (an IK bone that also carries weight is not the
 * foot); any joint when none qualifies. */
static uint32_t naming_joint(const cb_model *m, int32_t skin, const sole_vertex *v, size_t n, const bool *deforms)
{
    uint32_t bones = m->skins[skin].joint_count, best = 0, best_any = 0;
    double *sum = calloc(bones, sizeof *sum), top = -1, top_any = -1;
    if (!sum) return v[0].joint[0];
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 4; ++k)
            if (v[i].joint[k] < bones) sum[v[i].joint[k]] += v[i].weight[k];
    for (uint32_t j = 0; j < bones; ++j) {
        if (sum[j] > top_any) top_any = sum[j], best_any = j;
        bool control = rig_name_is_control(m->nodes[m->skins[skin].joints[j]].name);
        if (deforms[j] && !control && sum[j] > top) top = sum[j], best = j;
    }
    free(sum);
    return top > 0 ? best : best_any;
}

static int by_joint(const void *a, const void *b)
{
    const foot_sole *x = a, *y = b;
    return (x->joint > y->joint) - (x->joint < y->joint);
}

/* Per joint: the sole vertices it moves most, and their centre in the rest pose's ground plane. */
typedef struct joint_sole {
    uint32_t joint, count;
    double x, z;
} joint_sole;

static int by_count(const void *a, const void *b)
{
    const joint_sole *x = a, *y = b;
    if (x->count != y->count) return x->count < y->count ? 1 : -1;
    return (x->joint > y->joint) - (x->joint < y->joint);
}

/* Groups the sole vertices into feet: each vertex goes with the joint that moves it most, and
 * joints that share one foot's vertices (an IK bone and the leg's last, a heel and its toes: one
 * above the other, or centred within SOLE_LINK of the height) are one foot. The joint with the
 * most vertices leads; a paw wider than the gap between two paws stays two feet. */
static uint32_t group_soles(cb_sampler *s, const double *rest, sole_vertex *v, size_t n, double size, foot_sole *out,
                            uint32_t cap)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    uint32_t bones = m->skins[skin].joint_count, found = 0;
    joint_sole *js = calloc(bones, sizeof *js);
    int32_t *foot_of = malloc(bones * sizeof *foot_of);
    bool *deforms = malloc(bones * sizeof *deforms);
    uint32_t lead[CB_MAX_FEET_CAP];
    if (js && foot_of && deforms && cap <= CB_MAX_FEET_CAP) {
        rig_deforming_joints(m, skin, deforms);
        for (uint32_t j = 0; j < bones; ++j) js[j].joint = j, foot_of[j] = -1;
        for (size_t i = 0; i < n; ++i) {
            double h, xz[2];
            uint32_t j = dominant_joint(&v[i]);
            if (j >= bones) continue;
            foot_sole_at(&(foot_sole){j, 1, &v[i]}, rest, &h, xz);
            js[j].count++, js[j].x += xz[0], js[j].z += xz[1];
        }
        qsort(js, bones, sizeof *js, by_count);
        for (uint32_t i = 0; i < bones && js[i].count; ++i) {
            js[i].x /= js[i].count, js[i].z /= js[i].count;
            int32_t into = -1;
            for (uint32_t f = 0; f < found && into < 0; ++f) {
                const joint_sole *l = &js[lead[f]];
                if (same_leg(m, skin, js[i].joint, l->joint) || hypot(js[i].x - l->x, js[i].z - l->z) < SOLE_LINK * size)
                    into = (int32_t)f;
            }
            if (into < 0 && found < cap) lead[found] = i, into = (int32_t)found++;
            foot_of[js[i].joint] = into;
        }
        for (uint32_t f = 0; f < found; ++f) {
            out[f] = (foot_sole){0, 0, malloc(n * sizeof *v)};
            for (size_t i = 0; out[f].v && i < n; ++i) {
                uint32_t j = dominant_joint(&v[i]);
                if (j < bones && foot_of[j] == (int32_t)f) out[f].v[out[f].count++] = v[i];
            }
            out[f].joint = out[f].v ? naming_joint(m, skin, out[f].v, out[f].count, deforms) : js[lead[f]].joint;
        }
        qsort(out, found, sizeof *out, by_joint);
    }
    free(js), free(foot_of), free(deforms);
    return found;
}

/* Without a skinned mesh: the leaf joints in the lowest 15% of the joints' heights, each a foot
 * of one point (its bind position). */
static uint32_t leaf_joint_feet(cb_sampler *s, const double *rest, foot_sole *out, uint32_t cap, double *size)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_skin *sk = &m->skins[cb_sampler_skin(s)];
    uint32_t bones = sk->joint_count, n = 0;
    float *bind = malloc((size_t)bones * 3 * sizeof(float));
    if (!bind) return 0;
    palette_bind_positions(sk, bind);
    double ylo = INFINITY, yhi = -INFINITY, h, xz[2];
    for (uint32_t j = 0; j < bones; ++j) {
        sole_vertex one = {{bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]}, {j, 0, 0, 0}, {1, 0, 0, 0}};
        foot_sole_at(&(foot_sole){j, 1, &one}, rest, &h, xz);
        ylo = fmin(ylo, h), yhi = fmax(yhi, h);
    }
    *size = yhi - ylo > 0 ? yhi - ylo : 1;
    for (uint32_t j = 0; j < bones && n < cap; ++j) {
        bool leaf = true;
        for (uint32_t k = 0; k < bones && leaf; ++k)
            for (int32_t q = m->nodes[sk->joints[k]].parent; q >= 0 && leaf; q = m->nodes[q].parent) leaf = q != sk->joints[j];
        sole_vertex one = {{bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]}, {j, 0, 0, 0}, {1, 0, 0, 0}};
        foot_sole_at(&(foot_sole){j, 1, &one}, rest, &h, xz);
        if (!leaf || h > ylo + 0.15 * *size) continue;
        out[n].v = malloc(sizeof one);
        if (!out[n].v) break;
        out[n].v[0] = one, out[n].joint = j, out[n].count = 1, ++n;
    }
    free(bind);
    return n;
}

uint32_t foot_soles_find(cb_sampler *s, const double *rest, foot_sole *out, uint32_t cap, double *size)
{
    double lo[3], hi[3];
    *size = cb_skin_rest_bounds(s, lo, hi);
    size_t n = 0;
    sole_vertex *v = *size > 0 ? collect_sole_vertices(s, rest, lo[1], *size, &n) : NULL;
    uint32_t found = v && n ? group_soles(s, rest, v, n, *size, out, cap) : 0;
    free(v);
    return found ? found : leaf_joint_feet(s, rest, out, cap, size);
}

void foot_soles_free(foot_sole *f, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) free(f[i].v), f[i].v = NULL;
}

void foot_sole_at(const foot_sole *f, const double *mats, double *height, double xz[2])
{
    double x = 0, y = 0, z = 0;
    for (uint32_t i = 0; i < f->count; ++i) {
        const sole_vertex *sv = &f->v[i];
        double r[3] = {0, 0, 0};
        for (int k = 0; k < 4; ++k) {
            if (sv->weight[k] == 0) continue;
            const double *m = mats + (size_t)sv->joint[k] * 16;
            for (int c = 0; c < 3; ++c)
                r[c] += sv->weight[k] * (m[c] * sv->p[0] + m[4 + c] * sv->p[1] + m[8 + c] * sv->p[2] + m[12 + c]);
        }
        y += r[1], x += r[0], z += r[2];
    }
    *height = f->count ? y / f->count : 0;
    xz[0] = f->count ? x / f->count : 0, xz[1] = f->count ? z / f->count : 0;
}

/* Each sole vertex's first weighted part is set, not added to 0 as foot_sole_at does: 0 + t is t
 * but for a zero's sign (0 + -0 is +0), and the sign of a zero added to the sums is lost there
 * (they start at +0, and a sum from +0 never becomes -0: x + -x is +0), so the sums and the
 * result have foot_sole_at's bits. A vertex with no weight adds 0, which changes no sum: skipped;
 * one with a single weighted joint (most soles: a foot's vertices hang from the foot) adds its one
 * part straight to the sums, which is adding the same r. (Zeroing every vertex's 48 lanes, then
 * adding them up again, was two fifths of the function.) */
enum { SOLE_B = CB_SAMPLE_BATCH };

/* One weighted joint's part of a sole vertex in each lane, w (M p), added to `to` (or set). */
static inline void sole_part(double (*restrict to)[SOLE_B], const double (*restrict m)[SOLE_B], double w,
                             const double p[3], bool add)
{
    double p0 = p[0], p1 = p[1], p2 = p[2];
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < SOLE_B; ++i) {
            double t = w * (m[c][i] * p0 + m[4 + c][i] * p1 + m[8 + c][i] * p2 + m[12 + c][i]);
            to[c][i] = add ? to[c][i] + t : t;
        }
}

CB_TARGET_CLONES
void foot_sole_at_lanes(const foot_sole *f, const cb_joint_subset *sub, const double *lanes, double *height, double *x,
                        double *z)
{
    enum { B = SOLE_B };
    double sum[3][B] = {{0}}; /* x, y, z */
    for (uint32_t v = 0; v < f->count; ++v) {
        const sole_vertex *sv = &f->v[v];
        int weighted = (sv->weight[0] != 0) + (sv->weight[1] != 0) + (sv->weight[2] != 0) + (sv->weight[3] != 0);
        double r[3][B];
        for (int k = 0, parts = 0; k < 4; ++k) {
            if (sv->weight[k] == 0) continue;
            const double(*m)[B] = (const double(*)[B])(lanes + (size_t)sub->joint_slot[sv->joint[k]] * 16 * B);
            if (weighted == 1) sole_part(sum, m, sv->weight[k], sv->p, true);
            else sole_part(r, m, sv->weight[k], sv->p, parts++ > 0);
        }
        for (int c = 0; weighted > 1 && c < 3; ++c)
            for (int i = 0; i < B; ++i) sum[c][i] += r[c][i];
    }
    for (int i = 0; i < B; ++i) {
        height[i] = f->count ? sum[1][i] / f->count : 0;
        x[i] = f->count ? sum[0][i] / f->count : 0, z[i] = f->count ? sum[2][i] / f->count : 0;
    }
}
