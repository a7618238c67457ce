/* stride.c - planted feet, strides, ground speed and foot slide (stride.h). */
#include "crowdbake/stride.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palette_bake.h" /* palette_bind_positions */

/* Samples over one clip: 240 over a Cow's 1.2 s walk is 5 ms apart, well inside a stance. */
enum { STRIDE_SAMPLES = 240 };

/* The thresholds of a stride, as fractions of the model's height (size) where they are lengths.
 * A contact point must lift by 2% of the height to be stepping; it is planted while in the
 * lowest 15% of its own lift; a stride needs it planted for 15% of the cycle, stepping back at
 * 10% of the height per second or more (slower is shuffling on the spot), in a steady direction
 * (the mean velocity at least 70% of the mean speed) that agrees with the other feet (cosine
 * 0.7). */
#define LIFT_MIN 0.02
#define STANCE_BAND 0.15
#define STANCE_MIN 0.15
#define STEP_SPEED_MIN 0.1
#define STEADY_MIN 0.7
#define AGREE_MIN 0.7

/* A contact point: position = J_joint(t) * point. */
typedef struct contact {
    uint32_t joint, vertices;
    double point[3]; /* in the mesh's bind space */
    double at[3];    /* where the rest pose puts it */
} contact;

typedef struct track {
    double band; /* planted below this height */
    double *h;  /* height at each sample (STRIDE_SAMPLES + 1) */
    double *u;  /* horizontal velocity x, z over each interval (2 * STRIDE_SAMPLES) */
    bool *down; /* per interval: planted */
} track;

static void transform(const double *m, const double *p, double out[3])
{
    for (int k = 0; k < 3; ++k) out[k] = m[k] * p[0] + m[4 + k] * p[1] + m[8 + k] * p[2] + m[12 + k];
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

static int by_vertices(const void *a, const void *b)
{
    const contact *x = a, *y = b;
    if (x->vertices != y->vertices) return x->vertices < y->vertices ? 1 : -1;
    return (x->joint > y->joint) - (x->joint < y->joint);
}

static int by_joint(const void *a, const void *b)
{
    const contact *x = a, *y = b;
    return (x->joint > y->joint) - (x->joint < y->joint);
}

/* The contact points of the rest pose: per joint, the mean of the skinned vertices it moves most
 * that lie in the lowest 3% of the model's height; or, without a mesh, the leaf joints in the
 * lowest 15% of the joints' heights. Returns their count (at most CB_MAX_FEET, the ones with
 * the most vertices) and the model's height in *size. */
static uint32_t find_contacts(cb_sampler *s, const double *rest, contact *out, double *size)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    uint32_t bones = m->skins[skin].joint_count, n = 0;
    double lo[3], hi[3];
    *size = cb_skin_rest_bounds(s, lo, hi);
    contact *per_joint = calloc(bones, sizeof *per_joint);
    if (!per_joint) return 0;
    for (uint32_t pi = 0; pi < m->primitive_count && *size > 0; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        double *pos = malloc((size_t)prim->vertex_count * 3 * sizeof(double));
        if (!pos) break;
        cb_skin_positions(prim, rest, pos);
        for (uint32_t v = 0; v < prim->vertex_count; ++v) {
            if (pos[(size_t)v * 3 + 1] > lo[1] + 0.03 * *size) continue;
            uint32_t best = 0;
            for (int i = 1; i < 4; ++i)
                if (prim->weights[(size_t)v * 4 + i] > prim->weights[(size_t)v * 4 + best]) best = (uint32_t)i;
            contact *c = &per_joint[prim->joints[(size_t)v * 4 + best]];
            for (int k = 0; k < 3; ++k) c->point[k] += prim->positions[(size_t)v * 3 + k];
            c->vertices++;
        }
        free(pos);
    }
    /* The joints with the most vertices down there (ties: the first joint), then in joint order. */
    for (uint32_t j = 0; j < bones; ++j) per_joint[j].joint = j;
    qsort(per_joint, bones, sizeof *per_joint, by_vertices);
    /* Joints that share one foot's vertices (an IK bone and the leg's last, a heel and its toes)
     * are one contact (one above the other, or within 8% of the height: a human's feet stand 14%
     * apart, a quadruped's 17-27%): the one moving the most vertices down there stands for the foot. */
    for (uint32_t j = 0; j < bones && n < CB_MAX_FEET && per_joint[j].vertices; ++j) {
        contact c = per_joint[j];
        for (int k = 0; k < 3; ++k) c.point[k] /= c.vertices;
        transform(rest + (size_t)c.joint * 16, c.point, c.at);
        bool same = false;
        for (uint32_t i = 0; i < n && !same; ++i)
            same = same_leg(m, skin, c.joint, out[i].joint) ||
                   hypot(hypot(c.at[0] - out[i].at[0], c.at[1] - out[i].at[1]), c.at[2] - out[i].at[2]) < 0.08 * *size;
        if (!same) out[n++] = c;
    }
    qsort(out, n, sizeof *out, by_joint);
    free(per_joint);
    if (n > 0) return n;
    /* No skinned mesh: the lowest leaf joints, at their bind positions. */
    const cb_skin *sk = &m->skins[skin];
    float *bind = malloc((size_t)bones * 3 * sizeof(float));
    if (!bind) return 0;
    palette_bind_positions(sk, bind);
    double ylo = INFINITY, yhi = -INFINITY, p[3];
    for (uint32_t j = 0; j < bones; ++j) {
        double b[3] = {bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]};
        transform(rest + (size_t)j * 16, b, p);
        ylo = fmin(ylo, p[1]), yhi = fmax(yhi, p[1]);
    }
    *size = yhi - ylo > 0 ? yhi - ylo : 1;
    for (uint32_t j = 0; j < bones && n < CB_MAX_FEET; ++j) {
        bool leaf = true;
        for (uint32_t k = 0; k < bones && leaf; ++k)
            for (int32_t q = m->nodes[sk->joints[k]].parent; q >= 0 && leaf; q = m->nodes[q].parent) leaf = q != sk->joints[j];
        double b[3] = {bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]};
        transform(rest + (size_t)j * 16, b, p);
        if (leaf && p[1] <= ylo + 0.15 * *size) out[n++] = (contact){j, 1, {b[0], b[1], b[2]}, {p[0], p[1], p[2]}};
    }
    free(bind);
    return n;
}

/* Every contact's height and velocity over the clip, in the game's frame: the root's average
 * horizontal travel taken off as an in-place bake does (cb_root_travel_time). */
static bool sample_tracks(cb_sampler *s, const cb_clip_info *clip, const contact *cs, uint32_t n, track *tr)
{
    const cb_model *m = cb_sampler_model(s);
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count;
    double *mats = malloc((size_t)bones * 16 * sizeof(double));
    double *x = malloc((size_t)n * (STRIDE_SAMPLES + 1) * 2 * sizeof(double));
    bool ok = mats && x;
    double dt = clip->duration / STRIDE_SAMPLES, span = clip->t1 - clip->t0;
    for (uint32_t i = 0; ok && i <= STRIDE_SAMPLES; ++i) {
        double t = i * dt, tau = cb_root_travel_time(t, span, clip->duration, clip->loops), p[3];
        cb_sample_joint_matrices(s, clip->animation, clip->t0 + t, mats);
        for (uint32_t k = 0; k < n; ++k) {
            transform(mats + (size_t)cs[k].joint * 16, cs[k].point, p);
            tr[k].h[i] = p[1];
            x[((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2] = p[0] - clip->root_velocity[0] * tau;
            x[((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2 + 1] = p[2] - clip->root_velocity[2] * tau;
        }
    }
    for (uint32_t k = 0; ok && k < n; ++k)
        for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
            const double *a = x + ((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2;
            tr[k].u[i * 2] = (a[2] - a[0]) / dt, tr[k].u[i * 2 + 1] = (a[3] - a[1]) / dt;
        }
    free(mats), free(x);
    return ok;
}

/* Why a foot does not stride (before the feet are compared: FOOT_DISAGREES after). */
typedef enum foot_verdict { FOOT_STRIDES, FOOT_STILL, FOOT_SHORT, FOOT_SLOW, FOOT_UNSTEADY, FOOT_DISAGREES } foot_verdict;

/* One foot's stance: planted intervals, its mean backwards velocity while planted (mean[2]) and
 * whether it strides on its own. */
static foot_verdict foot_stance(track *tr, double size, cb_foot *f, double mean[2])
{
    double lo = INFINITY, hi = -INFINITY, speed_sum = 0;
    for (uint32_t i = 0; i <= STRIDE_SAMPLES; ++i) lo = fmin(lo, tr->h[i]), hi = fmax(hi, tr->h[i]);
    double band = tr->band = lo + STANCE_BAND * (hi - lo);
    uint32_t down = 0;
    mean[0] = mean[1] = 0;
    for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
        tr->down[i] = hi - lo >= LIFT_MIN * size && tr->h[i] <= band && tr->h[i + 1] <= band;
        if (!tr->down[i]) continue;
        ++down;
        mean[0] += tr->u[i * 2], mean[1] += tr->u[i * 2 + 1];
        speed_sum += hypot(tr->u[i * 2], tr->u[i * 2 + 1]);
    }
    if (down) mean[0] /= down, mean[1] /= down;
    f->stance = (double)down / STRIDE_SAMPLES;
    f->step_speed = hypot(mean[0], mean[1]);
    foot_verdict v = down == 0                               ? FOOT_STILL
                     : f->stance < STANCE_MIN                ? FOOT_SHORT
                     : f->step_speed < STEP_SPEED_MIN * size ? FOOT_SLOW
                     : f->step_speed * down < STEADY_MIN * speed_sum ? FOOT_UNSTEADY
                                                             : FOOT_STRIDES;
    f->strides = v == FOOT_STRIDES;
    return v;
}

/* The moment, in samples, the height crosses the band between samples a and a + 1. */
static double band_crossing(const track *tr, uint32_t a)
{
    double dh = tr->h[a + 1] - tr->h[a], x = dh != 0 ? (tr->band - tr->h[a]) / dh : 0;
    return a + (x < 0 ? 0 : x > 1 ? 1 : x);
}

/* A loop's planted intervals (runs of planted samples, the last one wrapping into the first) as
 * the times it lands and lifts. */
static void find_stances(const track *tr, double duration, cb_foot *f)
{
    const uint32_t n = STRIDE_SAMPLES;
    double dt = duration / n, land = -1;
    f->stance_count = 0;
    uint32_t first = 0; /* start after a lifted interval, so every stance is seen whole */
    while (first < n && tr->down[first]) ++first;
    if (first == n) return; /* always planted (or never lifts enough): no steps */
    for (uint32_t k = 1; k <= n; ++k) {
        uint32_t i = (first + k) % n, prev = (i + n - 1) % n;
        if (tr->down[i] && !tr->down[prev]) land = band_crossing(tr, prev) * dt;
        if (tr->down[i] && !tr->down[(i + 1) % n] && land >= 0 && f->stance_count < CB_MAX_STANCES) {
            double lift = band_crossing(tr, (i + 1) % n) * dt;
            f->stances[f->stance_count++] = (cb_stance){fmod(land, duration), fmod(lift, duration)};
            land = -1;
        }
    }
    for (uint32_t i = 1; i < f->stance_count; ++i) /* in time order */
        for (uint32_t j = i; j > 0 && f->stances[j].land < f->stances[j - 1].land; --j) {
            cb_stance t = f->stances[j];
            f->stances[j] = f->stances[j - 1], f->stances[j - 1] = t;
        }
}

/* Sum over the striding feet's planted intervals of |u + v d|: convex in v. */
static double slide_sum(const cb_stride *st, const track *tr, double v, uint32_t *count)
{
    double sum = 0;
    *count = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) {
        if (!st->feet[k].strides) continue;
        for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i)
            if (tr[k].down[i]) {
                sum += hypot(tr[k].u[i * 2] + v * st->heading[0], tr[k].u[i * 2 + 1] + v * st->heading[2]);
                ++*count;
            }
    }
    return sum;
}

/* The ground speed with the least total slide (golden-section search: deterministic, and the
 * sum is convex), then each foot's slide at it. */
static void fit_speed(cb_stride *st, const track *tr)
{
    double a = 0, b = 0;
    uint32_t count;
    for (uint32_t k = 0; k < st->foot_count; ++k) b = fmax(b, 2 * st->feet[k].step_speed);
    const double g = (sqrt(5) - 1) / 2;
    for (int it = 0; it < 100; ++it) {
        double c = b - g * (b - a), d = a + g * (b - a);
        if (slide_sum(st, tr, c, &count) <= slide_sum(st, tr, d, &count)) b = d;
        else a = c;
    }
    double v = st->speed = 0.5 * (a + b);
    st->slide_mean = count && v > 0 ? slide_sum(st, tr, v, &count) / count / v : 0;
    for (uint32_t k = 0; k < st->foot_count && v > 0; ++k) {
        cb_foot *f = &st->feet[k];
        double sum = 0;
        uint32_t n = 0;
        for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
            if (!tr[k].down[i]) continue;
            double slide = hypot(tr[k].u[i * 2] + v * st->heading[0], tr[k].u[i * 2 + 1] + v * st->heading[2]) / v;
            sum += slide, ++n;
            f->slide_worst = fmax(f->slide_worst, slide);
        }
        f->slide_mean = n ? sum / n : 0;
        if (f->strides) st->slide_worst = fmax(st->slide_worst, f->slide_worst);
    }
}

/* What the slide would be if the body's speed along the heading could vary row by row: at each
 * interval the speed that best plants the feet down then (the mean of their backward speeds),
 * its average over the cycle being the ground speed. */
static void measure_varying_travel(cb_stride *st, const track *tr, uint32_t rows)
{
    /* The best speed along the heading at each interval: the mean of the planted feet's. */
    double w[STRIDE_SAMPLES], o[STRIDE_SAMPLES + 1], v = st->speed;
    for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
        double sum = 0;
        uint32_t planted = 0;
        for (uint32_t k = 0; k < st->foot_count; ++k)
            if (st->feet[k].strides && tr[k].down[i])
                sum -= tr[k].u[i * 2] * st->heading[0] + tr[k].u[i * 2 + 1] * st->heading[2], ++planted;
        w[i] = planted ? sum / planted : v;
    }
    /* Its offset from travelling at v, made periodic (the drift taken off evenly), sampled at the
     * rows and blended linearly between them as a runtime would. */
    o[0] = 0;
    for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) o[i + 1] = o[i] + (w[i] - v) * (1.0 / STRIDE_SAMPLES);
    for (uint32_t i = 0; i <= STRIDE_SAMPLES; ++i) o[i] -= o[STRIDE_SAMPLES] * i / STRIDE_SAMPLES;
    double sum = 0;
    uint32_t count = 0;
    for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
        /* The offset's slope over the row interval holding this sample, per unit of cycle. */
        uint32_t r = (uint32_t)((double)i * rows / STRIDE_SAMPLES);
        uint32_t a = (uint32_t)lround((double)r * STRIDE_SAMPLES / rows), b = (uint32_t)lround((double)(r + 1) * STRIDE_SAMPLES / rows);
        double slope = b > a ? (o[b] - o[a]) * STRIDE_SAMPLES / (b - a) : 0, speed = v + slope;
        for (uint32_t k = 0; k < st->foot_count; ++k)
            if (st->feet[k].strides && tr[k].down[i])
                sum += hypot(tr[k].u[i * 2] + speed * st->heading[0], tr[k].u[i * 2 + 1] + speed * st->heading[2]), ++count;
    }
    st->slide_mean_varying = count && v > 0 ? sum / count / v : 0;
}

/* Whether the striding feet agree on a direction; sets the heading and marks the ones that
 * disagree. Returns how many stride. */
static uint32_t agree_on_heading(cb_stride *st, double (*means)[2], foot_verdict *verdicts)
{
    double dx = 0, dz = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k)
        if (st->feet[k].strides) dx += means[k][0] * st->feet[k].stance, dz += means[k][1] * st->feet[k].stance;
    double len = hypot(dx, dz);
    uint32_t n = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) {
        cb_foot *f = &st->feet[k];
        if (f->strides && len > 0 && (means[k][0] * dx + means[k][1] * dz) < AGREE_MIN * f->step_speed * len)
            f->strides = false, verdicts[k] = FOOT_DISAGREES;
        n += f->strides;
    }
    if (len > 0) st->heading[0] = -dx / len, st->heading[2] = -dz / len; /* planted feet go back */
    return n;
}

static void explain(cb_stride *st, const cb_clip_info *clip, const foot_verdict *verdicts, uint32_t striding)
{
    double smin = INFINITY, smax = 0, vmin = INFINITY, vmax = 0;
    uint32_t count[FOOT_DISAGREES + 1] = {0}, stepping = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) {
        const cb_foot *f = &st->feet[k];
        count[verdicts[k]]++;
        if (verdicts[k] == FOOT_STILL) continue;
        ++stepping;
        smin = fmin(smin, f->stance), smax = fmax(smax, f->stance);
        vmin = fmin(vmin, f->step_speed), vmax = fmax(vmax, f->step_speed);
    }
    char *w = st->why;
    size_t size = sizeof st->why;
    if (clip->duration <= 0)
        snprintf(w, size, "a single pose: no cycle to stride in");
    else if (st->foot_count == 0)
        snprintf(w, size, "no feet: nothing of the model touches the ground in its rest pose");
    else if (!clip->loops)
        snprintf(w, size, "plays once: a one-shot has no cycle to stride in");
    else if (stepping == 0)
        snprintf(w, size, "none of its %u feet lifts and comes down again", st->foot_count);
    else if (striding >= 2)
        snprintf(w, size, "%u of %u feet planted %.0f-%.0f%% of the cycle, stepping back together at %.3g-%.3g units/s",
                 striding, st->foot_count, 100 * smin, 100 * smax, vmin, vmax);
    else {
        int n = snprintf(w, size, "%u of %u feet step (planted %.0f-%.0f%% of the cycle, %.3g-%.3g units/s back), %u "
                         "stride:", stepping, st->foot_count, 100 * smin, 100 * smax, vmin, vmax, striding);
        static const char *const what[] = {NULL, NULL, "planted too briefly", "barely moving (shuffling)",
                                           "not steadily back", "against the others"};
        const char *sep = " ";
        for (int v = FOOT_SHORT; v <= FOOT_DISAGREES && n > 0 && (size_t)n < size; ++v)
            if (count[v]) n += snprintf(w + n, size - (size_t)n, "%s%u %s", sep, count[v], what[v]), sep = ", ";
    }
}

void cb_stride_measure(cb_sampler *s, const cb_clip_info *clip, cb_stride *out)
{
    memset(out, 0, sizeof *out);
    const cb_model *m = cb_sampler_model(s);
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count;
    double *rest = malloc((size_t)bones * 16 * sizeof(double)), size = 0;
    contact cs[CB_MAX_FEET];
    track tr[CB_MAX_FEET];
    double *buf = NULL;
    bool *down = NULL;
    if (rest) {
        cb_sample_joint_matrices(s, -1, 0, rest);
        out->foot_count = clip->duration > 0 ? find_contacts(s, rest, cs, &size) : 0;
    }
    uint32_t n = out->foot_count;
    buf = malloc((size_t)(n ? n : 1) * (STRIDE_SAMPLES * 3 + 1) * sizeof(double));
    down = malloc((size_t)(n ? n : 1) * STRIDE_SAMPLES * sizeof(bool));
    for (uint32_t k = 0; buf && down && k < n; ++k) {
        tr[k] = (track){.h = buf + (size_t)k * (STRIDE_SAMPLES * 3 + 1), .down = down + (size_t)k * STRIDE_SAMPLES};
        tr[k].u = tr[k].h + STRIDE_SAMPLES + 1;
        out->feet[k].joint = cs[k].joint;
        snprintf(out->feet[k].name, sizeof out->feet[k].name, "%s", m->nodes[m->skins[cb_sampler_skin(s)].joints[cs[k].joint]].name);
    }
    uint32_t striding = 0;
    foot_verdict verdicts[CB_MAX_FEET] = {FOOT_STILL};
    if (n && buf && down && sample_tracks(s, clip, cs, n, tr)) {
        double means[CB_MAX_FEET][2];
        for (uint32_t k = 0; k < n; ++k) {
            verdicts[k] = foot_stance(&tr[k], size, &out->feet[k], means[k]);
            if (clip->loops) find_stances(&tr[k], clip->duration, &out->feet[k]);
        }
        striding = clip->loops ? agree_on_heading(out, means, verdicts) : 0;
        out->stride = striding >= 2;
        if (out->stride) fit_speed(out, tr), measure_varying_travel(out, tr, clip->steps);
    }
    for (uint32_t k = 0; !out->stride && k < n; ++k) out->feet[k].strides = false; /* one foot is no stride */
    explain(out, clip, verdicts, striding);
    free(rest), free(buf), free(down);
}
