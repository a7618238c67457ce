/* stride.c - planted feet, strides, ground speed and foot slide (stride.h). */
#include "crowdbake/stride.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "foot_sole.h"
#include "sampler.h" /* cb_joint_subset */
#include "stride_feet.h"

/* Samples over one clip: 240 over a Cow's 1.2 s walk is 5 ms apart, well inside a stance. */
enum { STRIDE_SAMPLES = 240 };

/* The thresholds of a stride, as fractions of the model's height (size) where they are lengths.
 * A foot's sole must lift by 3% of the height to be stepping; it is planted while within 2% of
 * the height of its lowest (a band of the foot's own lift would follow how high it steps: 15% of
 * a gallop's leap is 7-9% of the height, a paw still in the air). A stride needs it planted for
 * 8% of the cycle (a leap's landing), stepping back at 10% of the height per second or more
 * (slower is shuffling on the spot), in a steady direction (the mean velocity at least half the
 * mean speed: a sole rolls as it plants and lifts) that agrees with the other feet (cosine 0.7). */
#define LIFT_MIN 0.03
#define STANCE_BAND 0.02
#define STANCE_MIN 0.08
#define STEP_SPEED_MIN 0.1
#define STEADY_MIN 0.5
#define AGREE_MIN 0.7

typedef struct track {
    double band; /* planted below this height */
    double *h;  /* the sole's height at each sample (STRIDE_SAMPLES + 1) */
    double *u;  /* horizontal velocity x, z over each interval (2 * STRIDE_SAMPLES) */
    bool *down; /* per interval: planted */
} track;

/* Where the feet are at samples idx[0 .. count) of the clip (ascending): each foot's sole height
 * into its track, its ground position (x, z) into x, in the game's frame: the root's average
 * horizontal travel taken off as an in-place bake does (cb_root_travel_time). Each sample's lane
 * is worked out alone, so the samples a batch holds do not change its bits. */
static void sample_feet_at(cb_sampler *s, const cb_clip_info *clip, const stride_feet *feet, uint32_t n,
                           const uint32_t *idx, uint32_t count, double *lanes, track *tr, double *x)
{
    double dt = clip->duration / STRIDE_SAMPLES, span = clip->t1 - clip->t0, times[CB_SAMPLE_BATCH];
    for (uint32_t first = 0; first < count; first += CB_SAMPLE_BATCH) {
        uint32_t batch = count - first < CB_SAMPLE_BATCH ? count - first : CB_SAMPLE_BATCH;
        for (uint32_t b = 0; b < batch; ++b) times[b] = clip->t0 + idx[first + b] * dt;
        cb_sample_joint_subset_batch(s, clip->animation, times, batch, feet->joints, lanes);
        for (uint32_t k = 0; k < n; ++k) {
            double h[CB_SAMPLE_BATCH], gx[CB_SAMPLE_BATCH], gz[CB_SAMPLE_BATCH];
            foot_sole_at_lanes(&feet->soles[k], feet->joints, lanes, h, gx, gz);
            for (uint32_t b = 0; b < batch; ++b) {
                uint32_t i = idx[first + b];
                double tau = cb_root_travel_time(i * dt, span, clip->duration, clip->loops);
                tr[k].h[i] = h[b];
                x[((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2] = gx[b] - clip->root_velocity[0] * tau;
                x[((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2 + 1] = gz[b] - clip->root_velocity[2] * tau;
            }
        }
    }
}

/* The screen (stride_measure_feet's `screen`): every SCREEN_EVERY-th sample first. A foot planted
 * for STANCE_MIN of the cycle (20 of the 240 intervals) in at most five stretches is planted on at
 * least SCREEN_PLANTED of them: r planted samples in a row hold at least floor(r / 4) of them, the
 * planted samples number at least 20 + R in R stretches, so at least (20 - 2 R) / 4, which is more
 * than 2 for R <= 5. What is planted among all the samples is planted among these (their lowest is
 * no lower, so their band is no lower). A stride needs two such feet. */
enum { SCREEN_EVERY = 4, SCREEN_PLANTED = 3 };

/* Whether two feet or more are planted on SCREEN_PLANTED of the screen's samples or more, within
 * the stance band of the lowest of them: false rules a stride out (see above). */
static bool feet_may_stride(const track *tr, uint32_t n, double size)
{
    uint32_t may = 0;
    for (uint32_t k = 0; k < n; ++k) {
        double lo = INFINITY;
        for (uint32_t i = 0; i <= STRIDE_SAMPLES; i += SCREEN_EVERY) lo = fmin(lo, tr[k].h[i]);
        uint32_t planted = 0;
        for (uint32_t i = 0; i <= STRIDE_SAMPLES; i += SCREEN_EVERY) planted += tr[k].h[i] <= lo + STANCE_BAND * size;
        may += planted >= SCREEN_PLANTED;
    }
    return may >= 2;
}

/* Every foot's sole height and velocity over the clip, the screen's samples first; with
 * `screen`, false in *strides when they rule a stride out, and the other samples not taken. */
static bool sample_tracks(cb_sampler *s, const cb_clip_info *clip, const stride_feet *feet, uint32_t n, track *tr,
                          bool screen, bool *strides)
{
    double *lanes = malloc(((size_t)feet->joints->joint_count + 1) * 16 * CB_SAMPLE_BATCH * sizeof(double));
    double *x = malloc((size_t)n * (STRIDE_SAMPLES + 1) * 2 * sizeof(double));
    uint32_t idx[STRIDE_SAMPLES + 1], screened = 0, rest = 0;
    bool ok = lanes && x;
    for (uint32_t i = 0; i <= STRIDE_SAMPLES; ++i) /* the screen's, then the others, each in order */
        if (i % SCREEN_EVERY == 0) idx[screened++] = i;
    for (uint32_t i = 0; i <= STRIDE_SAMPLES; ++i)
        if (i % SCREEN_EVERY) idx[screened + rest++] = i;
    if (ok) sample_feet_at(s, clip, feet, n, idx, screened, lanes, tr, x);
    *strides = !ok || !screen || feet_may_stride(tr, n, feet->size);
    if (ok && *strides) sample_feet_at(s, clip, feet, n, idx + screened, rest, lanes, tr, x);
    double dt = clip->duration / STRIDE_SAMPLES;
    for (uint32_t k = 0; ok && *strides && k < n; ++k)
        for (uint32_t i = 0; i < STRIDE_SAMPLES; ++i) {
            const double *a = x + ((size_t)k * (STRIDE_SAMPLES + 1) + i) * 2;
            tr[k].u[i * 2] = (a[2] - a[0]) / dt, tr[k].u[i * 2 + 1] = (a[3] - a[1]) / dt;
        }
    free(lanes), free(x);
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
    double band = tr->band = lo + STANCE_BAND * size;
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
    /* The ranges quoted: of the striding feet where the clip strides (a foot left out, shuffling
     * on the spot, is not among those stepping back together), else of every foot that steps. */
    double smin = INFINITY, smax = 0, vmin = INFINITY, vmax = 0;
    uint32_t count[FOOT_DISAGREES + 1] = {0}, stepping = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) {
        const cb_foot *f = &st->feet[k];
        count[verdicts[k]]++;
        if (verdicts[k] == FOOT_STILL) continue;
        ++stepping;
        if (striding >= 2 && !f->strides) continue;
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

bool stride_feet_find(cb_sampler *s, stride_feet *feet)
{
    memset(feet, 0, sizeof *feet);
    const cb_model *m = cb_sampler_model(s);
    double *rest = malloc((size_t)m->skins[cb_sampler_skin(s)].joint_count * 16 * sizeof(double));
    if (!rest) return false;
    cb_sample_joint_matrices(s, -1, 0, rest);
    feet->count = foot_soles_find(s, rest, feet->soles, CB_MAX_FEET, &feet->size);
    free(rest);
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count;
    bool *wanted = calloc(bones ? bones : 1, sizeof *wanted);
    for (uint32_t k = 0; wanted && k < feet->count; ++k)
        for (uint32_t v = 0; v < feet->soles[k].count; ++v)
            for (int w = 0; w < 4; ++w) /* the joints foot_sole_at reads */
                if (feet->soles[k].v[v].weight[w] != 0 && feet->soles[k].v[v].joint[w] < bones)
                    wanted[feet->soles[k].v[v].joint[w]] = true;
    feet->joints = wanted ? cb_joint_subset_create(s, wanted) : NULL;
    free(wanted);
    if (!feet->joints) stride_feet_free(feet);
    return feet->joints != NULL;
}

void stride_feet_free(stride_feet *feet)
{
    foot_soles_free(feet->soles, feet->count);
    cb_joint_subset_free(feet->joints);
    feet->count = 0, feet->joints = NULL;
}

void stride_tracks_free(stride_tracks *t)
{
    free(t->buf), free(t->down);
    memset(t, 0, sizeof *t);
}

/* The per-foot tracks over one buffer of heights and velocities and one of planted flags. */
static void tracks_view(const stride_tracks *t, track *tr)
{
    for (uint32_t k = 0; k < t->feet; ++k) {
        tr[k] = (track){.h = t->buf + (size_t)k * (STRIDE_SAMPLES * 3 + 1), .down = t->down + (size_t)k * STRIDE_SAMPLES};
        tr[k].u = tr[k].h + STRIDE_SAMPLES + 1;
    }
}

/* A clip the screen ruled out: no stride, and why; its feet's stances and speeds not measured. */
static void explain_screened(cb_stride *st)
{
    snprintf(st->why, sizeof st->why, "no stride: fewer than two of its %u feet are planted (within %.0f%% of the model's "
             "height of their lowest) on %d or more of %d evenly spaced samples of the cycle, as a foot planted for %.0f%% "
             "of it would be; the feet were measured no further", st->foot_count, 100 * STANCE_BAND, SCREEN_PLANTED,
             STRIDE_SAMPLES / SCREEN_EVERY + 1, 100 * STANCE_MIN);
}

void stride_measure_feet(cb_sampler *s, const cb_clip_info *clip, const stride_feet *feet, bool screen, cb_stride *out,
                         stride_tracks *keep)
{
    memset(out, 0, sizeof *out);
    memset(keep, 0, sizeof *keep);
    const cb_model *m = cb_sampler_model(s);
    uint32_t n = out->foot_count = clip->duration > 0 ? feet->count : 0;
    const foot_sole *soles = feet->soles;
    track tr[CB_MAX_FEET];
    keep->buf = malloc((size_t)(n ? n : 1) * (STRIDE_SAMPLES * 3 + 1) * sizeof(double));
    keep->down = malloc((size_t)(n ? n : 1) * STRIDE_SAMPLES * sizeof(bool));
    keep->feet = keep->buf && keep->down ? n : 0;
    tracks_view(keep, tr);
    for (uint32_t k = 0; k < n; ++k) {
        out->feet[k].joint = soles[k].joint;
        snprintf(out->feet[k].name, sizeof out->feet[k].name, "%s", m->nodes[m->skins[cb_sampler_skin(s)].joints[soles[k].joint]].name);
    }
    uint32_t striding = 0;
    foot_verdict verdicts[CB_MAX_FEET] = {FOOT_STILL};
    bool may_stride = true, sampled = n && keep->feet && sample_tracks(s, clip, feet, n, tr, screen, &may_stride);
    if (sampled && !may_stride) { /* a quarter sampled: nothing to measure again from */
        stride_tracks_free(keep); /* now, for the next clip's to reuse */
        explain_screened(out);
        return;
    }
    if (sampled) {
        double means[CB_MAX_FEET][2];
        for (uint32_t k = 0; k < n; ++k) {
            verdicts[k] = foot_stance(&tr[k], feet->size, &out->feet[k], means[k]);
            if (clip->loops) find_stances(&tr[k], clip->duration, &out->feet[k]);
        }
        striding = clip->loops ? agree_on_heading(out, means, verdicts) : 0;
        out->stride = striding >= 2;
        if (out->stride) fit_speed(out, tr), measure_varying_travel(out, tr, clip->steps);
    }
    for (uint32_t k = 0; !out->stride && k < n; ++k) out->feet[k].strides = false; /* one foot is no stride */
    explain(out, clip, verdicts, striding);
}

void stride_varying_at(cb_stride *st, const stride_tracks *kept, uint32_t rows)
{
    track tr[CB_MAX_FEET];
    if (!st->stride || kept->feet != st->foot_count) return;
    tracks_view(kept, tr);
    measure_varying_travel(st, tr, rows);
}

void cb_stride_measure(cb_sampler *s, const cb_clip_info *clip, cb_stride *out)
{
    stride_feet feet;
    stride_tracks tracks;
    if (!(clip->duration > 0 ? stride_feet_find(s, &feet) : (memset(&feet, 0, sizeof feet), true))) {
        memset(out, 0, sizeof *out);
        explain(out, clip, (foot_verdict[CB_MAX_FEET]){FOOT_STILL}, 0);
        return;
    }
    stride_measure_feet(s, clip, &feet, false, out, &tracks);
    stride_tracks_free(&tracks);
    stride_feet_free(&feet);
}
