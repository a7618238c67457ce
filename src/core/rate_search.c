/* rate_search.c - see runtime.h: each clip's frame rate chosen by visible error (cb_choose_rates),
 * what the bake job decides its auto rates with. */
#include "crowdbake/runtime.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>

#include "cb_math.h"
#include "global_timed.h" /* global rows on their keys, asked for */
#include "key_grid.h"
#include "local_rate.h"   /* local rows' rates */
#include "palette_bake.h" /* palette_bake_with_facts */

/* ---- error-driven frame rate ---- */

/* One clip's search: its probes so far. Both families, both kinds of rows and the closing
 * measurement ask for some rates twice (the key rate's multiples are common rates too), and a
 * probe is a whole bake of the clip: each rate is baked once for each kind of rows. */
typedef struct probe {
    double fps, goal, error;
    bool fit;
    int family; /* FAMILY_KEYS or FAMILY_COMMON: the law it stands for (predicted_law) */
    bool deferred; /* sampled rows at max_fps missing their goal: its exact error not yet measured (defer_exact) */
} probe;
typedef struct clip_search {
    cb_sampler *s;
    const cb_bake_options *o;
    const cb_clip_plan *clip;
    bool fit;                        /* the kind of rows probed now: fitted, or sampled */
    double max_fps;
    probe done[64];
    uint32_t count;
    int family;                      /* the family of rates searched now: FAMILY_KEYS or FAMILY_COMMON */
    const palette_skin_facts *facts; /* the skin's, settled once for every bake of the search */
    palette_probe probe;             /* the clip's analysis and exact poses, for every probe */
    bool needed_later;               /* a clip over its goal at max_fps: its caller searches on (fps_needed unset) */
    bool fitted_follow;              /* fitted rows are probed after sampled ones at each rate (CB_ROWS_BEST) */
} clip_search;

/* The visible error of the clip baked alone at `fps` with the rows cs->fit says: the bake
 * measures it (the encoding, and the blend halfway between every two rows; fitted rows at the
 * quarter points too). goal > 0: exact when within it; above it, the measurement may stop early
 * (any value above the goal decides the search alike). Every bake of the search measures the
 * same vertices from the same bind pose (the skin's, whatever the clip): what depends on the
 * skin alone is settled once (cs->facts), not once a bake, and the clip is analyzed once
 * (cs->probe.analysis). The probes' times coincide (a probe's blends are the rows of one at
 * twice its rate, a fitted probe's mid-rows too): each time's exact matrices are sampled once
 * for the clip (cs->probe.poses). */
static double clip_error_at(clip_search *cs, double fps, double goal, cb_error *err)
{
    cb_bake_options one = *cs->o;
    one.fps = fps;
    one.threads = 1;
    one.error_goal = goal;
    one.fit = false;
    cb_clip_plan plan = *cs->clip;
    plan.fps = fps;
    plan.fit = cs->fit;
    cb_palette p;
    if (palette_bake_with_facts(cs->s, &one, &plan, 1, cs->facts, &cs->probe, &p, err)) return INFINITY;
    double worst = p.visible_error;
    cb_palette_free(&p);
    return worst;
}

/* A probe already made answers as probe_error would (a measurement, not a prediction): one
 * measured exactly (no goal, or within its goal) any goal; one stopped above its goal any goal up
 * to that one, which it misses alike. */
static bool probed(const clip_search *cs, double fps, double goal, double *error)
{
    for (uint32_t i = 0; i < cs->count; ++i) {
        const probe *d = &cs->done[i];
        if (d->fps == fps && d->fit == cs->fit && (d->goal == 0 || d->error <= d->goal || (goal > 0 && goal <= d->goal)))
            return *error = d->error, true;
    }
    return false;
}

/* Whether a probe at fps measures with its goal though main's rule measures max_fps exactly at
 * once: sampled rows at max_fps where fitted rows follow them. Their exact error is read only
 * where fitted rows miss at max_fps too (choose_clip's last lines, through probed) or where the
 * 1/fps^2 law takes it as a nearest probe (nearest_law): both measure it then (defer_exact),
 * the same bits as measured at once; where fitted rows meet at max_fps, nothing reads it (Cow's
 * Attack_Kick: 120 fps sampled rows measured in full, 7.5 M instructions, for nothing). */
static bool defer_exact(const clip_search *cs, double fps)
{
    return fps == cs->max_fps && !cs->fit && cs->fitted_follow;
}

#define FITTED_AT_BEST 0.5 /* fitted rows' error over sampled rows' at the same rate, at best */

/* Whether a probe at fps is of sampled rows that fitted rows may follow at the same rate, under
 * max_fps: where the sampled rows miss, the fitted ones are baked only if half the sampled rows'
 * error meets the goal (rate_meets). Such a probe measures to twice the goal, not to the goal:
 * a miss within twice it is exact, and one stopped above it settles that the fitted rows miss
 * too, without baking them. (Fox's Survey walking down from 24 fps: sampled rows stopped at 1.05
 * and 1.8 times the goal at 20 and 12 fps, off its keys, and fitted rows were baked at both and
 * missed, a tenth of the bake; measured in full, the sampled rows err 3.0 and 8.6 mm/m there.) */
static bool sampled_before_fitted(const clip_search *cs, double fps)
{
    return !cs->fit && cs->fitted_follow && fps < cs->max_fps;
}

/* A probe's record: a new one, or the exact error of a deferred one in its place (the probes in
 * the same order as measured at once). */
static void record_probe(clip_search *cs, probe made)
{
    for (uint32_t i = 0; i < cs->count; ++i)
        if (cs->done[i].deferred && cs->done[i].fps == made.fps && cs->done[i].fit == made.fit) {
            made.family = cs->done[i].family; /* the walk's family when first probed */
            cs->done[i] = made;
            return;
        }
    if (cs->count < sizeof cs->done / sizeof cs->done[0]) cs->done[cs->count++] = made;
}

/* clip_error_at, once per rate and kind of rows. A value measured exactly (no goal, or within
 * its goal) answers any goal; one above its goal only the same goal. max_fps is measured
 * exactly at once: when it is probed every lower common rate failed, and a clip that fails it
 * too needs its exact error there anyway (choose_clip's last lines); but for sampled rows that
 * fitted rows follow, which measure with the goal and leave the exact error for when it is
 * read (defer_exact). */
static double probe_error(clip_search *cs, double fps, double goal, cb_error *err)
{
    double known;
    if (probed(cs, fps, goal, &known)) return known;
    bool defer = defer_exact(cs, fps) && goal > 0;
    if (fps == cs->max_fps && !defer) goal = 0;
    else if (goal > 0 && sampled_before_fitted(cs, fps)) goal /= FITTED_AT_BEST;
    double e = clip_error_at(cs, fps, goal, err);
    if (!err->status) record_probe(cs, (probe){fps, goal, e, cs->fit, cs->family, defer && !(e <= goal)});
    return e;
}

/* A deferred probe's exact error, measured now (as probe_error would have at once). */
static void settle_deferred(clip_search *cs, probe *d, cb_error *err)
{
    bool fit = cs->fit;
    cs->fit = d->fit;
    double e = clip_error_at(cs, d->fps, 0, err);
    cs->fit = fit;
    if (!err->status) d->goal = 0, d->error = e, d->deferred = false;
}

/* The two families of rates a clip may bake at: its key rate's multiples and fractions, whose
 * rows land on keys, and the common rates. */
enum { FAMILY_KEYS, FAMILY_COMMON };

/* The blend's error falls as the square of the row spacing (a chord under an arc): a clip that
 * errs e at f fps errs about e (f / g)^2 at g fps, within a few percent on Cow and Fox (Walk,
 * sampled: 0.0185 at 24 fps, 0.00466 at 48, 0.00209 at 72), and fitted rows err at best half of
 * what sampled ones do at the same rate (0.50-0.71 of it on Cow and Husky). So the probe nearest
 * in rate, per kind of rows and family of rates, predicts through its error x fps^2 a lower bound
 * for a rate not yet baked: for fitted rows, also half of what the sampled ones predict; for a
 * common rate with no common probe yet, what the key rates predict (rows between keys err
 * more). The nearest probe, not the largest error x fps^2 of any: the law holds locally, and
 * slow clips' errors fall slower than it at low rates (the sample bird's glide, sampled: 1.4e-4
 * at 20 fps, 3.4e-4 at 10, not 5.7e-4), so a far probe would rule out a rate that meets. A rate
 * predicted over one and a half times the goal is taken as a miss without baking it. Every rate
 * chosen is still one that was baked and met its goal; the prediction only spares bakes that
 * would miss, and fitted bakes cost several sampled ones (they sample every mid-row to fit the
 * rows). max_fps is always baked: its exact error is what an unmet goal reports. */
#define PREDICTED_MISS 1.5

/* The error x fps^2 of the probe of this kind and family nearest to fps (ties: the larger), 0
 * when there is none. A deferred probe that is nearest (or tied) has its exact error measured
 * first, so the law is the one of probes measured at once. */
static double nearest_law(clip_search *cs, bool fit, int family, double fps, cb_error *err)
{
    double law = 0, distance = INFINITY;
    for (uint32_t i = 0; i < cs->count; ++i) {
        const probe *d = &cs->done[i];
        if (d->fit == fit && d->family == family && isfinite(d->error)) distance = fmin(distance, fabs(log(d->fps / fps)));
    }
    for (uint32_t i = 0; i < cs->count && !err->status; ++i) {
        probe *d = &cs->done[i];
        if (d->deferred && d->fit == fit && d->family == family && fabs(log(d->fps / fps)) == distance)
            settle_deferred(cs, d, err);
    }
    distance = INFINITY;
    for (uint32_t i = 0; i < cs->count; ++i) {
        const probe *d = &cs->done[i];
        if (d->fit != fit || d->family != family || !isfinite(d->error)) continue;
        double far = fabs(log(d->fps / fps)), here = d->error * d->fps * d->fps;
        if (far < distance || (far == distance && here > law)) law = here, distance = far;
    }
    return law;
}

static double predicted_law(clip_search *cs, bool fit, int family, double fps, cb_error *err)
{
    double law = nearest_law(cs, fit, family, fps, err);
    if (!(law > 0)) law = nearest_law(cs, fit, FAMILY_KEYS, fps, err);
    return fit ? fmax(law, FITTED_AT_BEST * predicted_law(cs, false, family, fps, err)) : law;
}

static bool predicted_miss(clip_search *cs, double fps, double max_error, cb_error *err)
{
    return fps < cs->max_fps &&
           predicted_law(cs, cs->fit, cs->family, fps, err) / (fps * fps) > PREDICTED_MISS * max_error;
}

static double rate_error(clip_search *cs, double fps, double max_error, cb_error *err)
{
    double known;
    if (probed(cs, fps, fps == cs->max_fps ? 0 : max_error, &known)) return known;
    bool miss = predicted_miss(cs, fps, max_error, err);
    return err->status ? INFINITY : miss ? INFINITY : probe_error(cs, fps, max_error, err);
}

/* The lowest of the increasing `rates` (up to max_fps, and under `below` unless it is 0) at
 * which the clip's error is within max_error, 0 when none is, with its error. Within one family
 * of rates the error falls as the rate rises, so the search walks from one rate: down while the
 * rates meet the goal, else up until one does. A probe that misses the goal stops measuring at
 * the first row above it, and most of a search's probes miss; one that meets it is measured in
 * full, and walking rather than bisecting measures few besides the answer. It starts at the
 * likeliest answer (`first`), or under a bound at the highest rate under it: the bound is a rate
 * already known to meet the goal, and a miss there settles that nothing lower meets it. */
static double lowest_rate(clip_search *cs, const double *rates, size_t n, size_t first, double below,
                          double max_error, double *error, cb_error *err)
{
    while (n > 0 && (rates[n - 1] > cs->max_fps || (below > 0 && rates[n - 1] >= below))) --n;
    if (n == 0) return 0;
    size_t at = below > 0 || first >= n ? n - 1 : first;
    double e = rate_error(cs, rates[at], max_error, err);
    if (e <= max_error) { /* down while the rates meet it */
        for (*error = e; at > 0 && !err->status && (e = rate_error(cs, rates[at - 1], max_error, err)) <= max_error; --at)
            *error = e;
        return err->status ? 0 : rates[at];
    }
    while (++at < n && !err->status)
        if ((e = rate_error(cs, rates[at], max_error, err)) <= max_error) return *error = e, rates[at];
    return 0;
}

/* The rates a clip may bake at: common rates, and the clip's key rate with its multiples and
 * fractions. */
typedef struct rate_families {
    const double *common;
    size_t n_common, n_aligned;
    double aligned[16];
    size_t key;         /* the key rate's place in aligned (probed first) */
} rate_families;
static const double common_rates[] = {2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 48, 60, 90, 120};
enum { COMMON_FIRST = 11 }; /* 30 fps: where a search of the common rates alone starts */

/* A key rate's multiples past the 4th: only above the common rates (a clip allowed past
 * CB_AUTO_MAX_FPS, a fast transient), where no common rate is left and only rows on its keys
 * come near its goal (Robot_Punch, 24 fps keys: 0.91 mm/m at 216 fps fitted); at most 10 of them
 * (the lowest), so the search stays a few probes. Under it the families are as they were. */
static void add_high_multiples(rate_families *f, double key_rate, double max_fps)
{
    double top = common_rates[sizeof common_rates / sizeof common_rates[0] - 1];
    for (double k = 5; f->n_aligned < 16 && k * key_rate <= max_fps; ++k)
        if (k * key_rate > top) f->aligned[f->n_aligned++] = round(k * key_rate * 1000) / 1000;
}

/* The key family: fractions and multiples of the clip's key rate, the coarsest grid within max_fps
 * that holds every key (key_grid.h), else its shortest key gap's (Fox's Run: keys every 1/24 s,
 * then on a grid 1/120 s off it; its family is 30, 60, 120 fps, whose 120 is its answer, not
 * 24, 48, 96, which miss it). */
static rate_families families_of(const cb_animation *a, double max_fps)
{
    static const double factors[] = {0.25, 0.5, 1, 2, 3, 4};
    rate_families f = {common_rates, sizeof common_rates / sizeof common_rates[0], 0, {0}, 2};
    double key = cb_animation_key_interval(a);
    uint32_t m = cb_key_grid_divisions(a, a->t0, 0, max_fps);
    double step = key / (m ? m : 1);
    for (size_t i = 0; key > 0 && i < 6; ++i) f.aligned[f.n_aligned++] = round(factors[i] / step * 1000) / 1000;
    if (key > 0) add_high_multiples(&f, 1 / step, max_fps);
    return f;
}

/* Both families' rates up to max_fps, merged in increasing order, each with its family (a rate
 * in both is the keys': its rows land on keys, and the keys' law predicts it); returns how many. */
typedef struct candidate {
    double fps;
    int family;
} candidate;

static size_t merged_rates(const rate_families *f, double max_fps, candidate *out)
{
    size_t n = 0, a = 0, b = 0;
    while (a < f->n_aligned || b < f->n_common) {
        bool take_aligned = b >= f->n_common || (a < f->n_aligned && f->aligned[a] <= f->common[b]);
        candidate c = take_aligned ? (candidate){f->aligned[a++], FAMILY_KEYS} : (candidate){f->common[b++], FAMILY_COMMON};
        if (c.fps > max_fps || (n > 0 && out[n - 1].fps == c.fps)) continue; /* a rate in both: the keys' (first) */
        out[n++] = c;
    }
    if (n == 0 || out[n - 1].fps < max_fps) out[n++] = (candidate){max_fps, FAMILY_COMMON}; /* always a candidate */
    return n;
}

/* The rate `c` when the clip meets max_error there with sampled rows, else with fitted rows (of
 * the kinds `rows` allows; cs->fit says which, *error its error), 0 when neither does. Fitted
 * rows err at least half what sampled rows do at the same rate, and a fitted probe costs several
 * sampled ones (it samples every mid-row and fits them): where the law rules out sampled rows
 * but not fitted ones, the sampled rows are baked first, and their error at this very rate
 * (rather than the law's, from other rates) decides whether the fitted probe is worth making.
 * (Cow's Gallop at 40 fps: the law from 24 fps put fitted rows at 1.1 times the goal; sampled rows
 * there err 4 times it, off the key grid.) Fitted rows are baked only where even their best case,
 * half the sampled rows' error there, meets the goal, walking up and walking down alike. (The walk
 * down baked them wherever the law's 1.5x margin left them open, sampled rows up to 3 times the
 * goal: every such probe on Cow, Husky, Fox and the robot missed, fitted rows erring 0.50-0.94 of
 * what sampled rows do at the same rate there, measured in full, and they were a sixth of Fox's
 * bake and a tenth of the robot's; speed43e.) A sampled miss's error is where its measurement
 * stopped, at most its maximum, so the test is no looser than the best case it stands for; the
 * sampled probe measures to twice the goal (sampled_before_fitted), so that it decides the test
 * where a probe stopped at the goal could not. max_fps is baked both ways: its exact errors are
 * what an unmet goal reports. */
static double rate_meets(clip_search *cs, cb_rows rows, candidate c, double max_error, double *error, cb_error *err)
{
    double sampled = INFINITY;
    for (int fit = rows == CB_ROWS_FITTED; fit <= (rows != CB_ROWS_SAMPLED) && !err->status; ++fit) {
        cs->fit = fit, cs->family = c.family;
        if (fit && c.fps < cs->max_fps && rows == CB_ROWS_BEST && !(sampled * FITTED_AT_BEST <= max_error))
            continue;
        double e = rate_error(cs, c.fps, max_error, err);
        if (e <= max_error) return *error = e, c.fps;
        sampled = e;
        double known;
        if (fit || rows != CB_ROWS_BEST || probed(cs, c.fps, max_error, &known)) continue;
        cs->fit = true; /* sampled rows ruled out by the law: baked only where fitted rows are not */
        if (predicted_miss(cs, c.fps, max_error, err) || err->status) continue;
        cs->fit = false;
        if ((e = sampled = probe_error(cs, c.fps, max_error, err)) <= max_error) return *error = e, c.fps;
    }
    return 0;
}

/* The clip's lowest rate and kind of rows within max_error, up to max_fps (0 when none is), with
 * its error into *error and the kind into cs->fit: one walk over both families' rates together,
 * sampled rows then fitted rows at each rate (sampled rows win a tie). It starts at the key rate
 * (the likeliest answer; 30 fps without one), and goes up from there while both kinds miss, or
 * down from where one meets. Going down, a family of rates is left at its first rate where both
 * kinds miss (within a family the error falls as the rate rises: nothing lower in it meets), and
 * the walk ends when both are. The 1/fps^2 law (rate_error) rules out, without baking them, rates
 * that would miss by far. (Searching sampled rows to their answer first, then fitted rows under
 * it, baked both kinds' answers and the rates between: Husky's Gallop probed 96, 90 and 120 fps
 * sampled and 96 fitted before 72 fitted won.) `rows` allows one kind or both. */
static double lowest_rate_walk(clip_search *cs, const rate_families *f, cb_rows rows, double max_error, double *error,
                               cb_error *err)
{
    candidate rates[sizeof common_rates / sizeof common_rates[0] + 17];
    size_t n = merged_rates(f, cs->max_fps, rates), at = 0;
    double key = f->n_aligned > f->key ? f->aligned[f->key] : common_rates[COMMON_FIRST], found = 0;
    while (at + 1 < n && rates[at + 1].fps <= key) ++at; /* the highest rate up to the key rate */
    for (; at < n && found == 0 && !err->status; ++at) /* up from the key rate until one kind meets */
        found = rate_meets(cs, rows, rates[at], max_error, error, err);
    if (found == 0) return 0;
    bool left[2] = {false, false}; /* [family]: a rate of it where both kinds missed */
    for (size_t i = at - 1; i-- > 0 && !(left[FAMILY_KEYS] && left[FAMILY_COMMON]) && !err->status;) {
        if (left[rates[i].family]) continue;
        bool fit = cs->fit; /* the answer's kind so far */
        double e = 0, r = rate_meets(cs, rows, rates[i], max_error, &e, err);
        if (r > 0) found = r, *error = e;
        else cs->fit = fit, left[rates[i].family] = true;
    }
    return err->status ? 0 : found;
}

/* A clip over its goal at max_fps: the lowest rate up to CB_FPS_LIMIT (a ladder of multiples of
 * max_fps) within it, for the rows cs->fit says, or 0 when none is (the encoding's own error
 * stays over the goal). Only a failing bake pays for it: it is what the message suggests. */
static double rate_that_meets(clip_search *cs, double max_error, cb_error *err)
{
    static const double steps[] = {1.5, 2, 3, 4, 6, 8, 12, 16};
    double ladder[9]; /* the steps, and CB_FPS_LIMIT after them */
    size_t n = 0;
    for (size_t i = 0; i < 8 && cs->max_fps * steps[i] <= CB_FPS_LIMIT; ++i) ladder[n++] = ceil(cs->max_fps * steps[i]);
    if (n == 0 || ladder[n - 1] < CB_FPS_LIMIT) ladder[n++] = CB_FPS_LIMIT;
    double ignored = 0, cap = cs->max_fps;
    bool follow = cs->fitted_follow;
    cs->max_fps = CB_FPS_LIMIT, cs->family = FAMILY_COMMON, cs->fitted_follow = false; /* one kind: exact at its top */
    double fps = lowest_rate(cs, ladder, n, 0, 0, max_error, &ignored, err);
    cs->max_fps = cap, cs->fitted_follow = follow;
    return fps;
}

/* One clip's rate and rows: the fewest rows within max_error (lowest_rate_walk; sampled rows win
 * ties, being the exact poses themselves: nearest-row playback and anything reading a row alone
 * sees no fitting error). `rows` forces one kind. Over the goal even at max_fps: the kind with
 * the lower error there, and the rate that would meet it (c->fps_needed). */
static double choose_clip(clip_search *cs, const rate_families *f, cb_rows rows, double max_error, cb_rate_choice *c,
                          cb_error *err)
{
    cs->fitted_follow = rows == CB_ROWS_BEST;
    double e = INFINITY, r = lowest_rate_walk(cs, f, rows, max_error, &e, err);
    memset(c, 0, sizeof *c);
    if (err->status) return cs->max_fps;
    if (r > 0) { /* other_fps stays 0: sampled rows miss at r (the walk stops at the fewest rows) */
        c->met = true, c->fitted = cs->fit, c->error = e;
        return r;
    }
    /* None met: the exact error at max_fps of each kind allowed, the lower one taken. */
    cs->fit = rows != CB_ROWS_SAMPLED;
    double at_max = probe_error(cs, cs->max_fps, 0, err);
    if (rows == CB_ROWS_BEST && !err->status) {
        cs->fit = false;
        double sampled = probe_error(cs, cs->max_fps, 0, err);
        cs->fit = !(sampled < at_max);
        at_max = fmin(at_max, sampled);
    }
    c->fitted = cs->fit, c->error = at_max, c->met = at_max <= max_error;
    if (!err->status && !c->met && !cs->needed_later) c->fps_needed = rate_that_meets(cs, max_error, err);
    return cs->max_fps;
}

static double choose_clip_fps(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *clip, double max_error,
                              double max_fps, cb_rows rows, cb_rate_choice *c, const palette_skin_facts *facts,
                              pose_cache *poses, bool fresh, pose_batch *batch, bool needed_later, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    rate_families f = families_of(&m->animations[clip->animation], max_fps);
    /* Analyzed at the lowest rate, the likeliest within the frame limit; where it fails, each
     * probe analyzes the clip itself and fails as it would. */
    cb_clip_info analysis;
    cb_error unanalyzed = {0};
    /* (or its analysis from before the search, kept with its poses, framed at that rate) */
    bool analyzed = (poses && !fresh &&
                     palette_take_kept_analysis(poses, s, clip->animation, clip->loop, common_rates[0], &o->limits, &analysis)) ||
                    !cb_clip_analyze(s, clip->animation, common_rates[0], clip->loop, &o->limits, &analysis, &unanalyzed);
    clip_search cs = {.s = s, .o = o, .clip = clip, .max_fps = max_fps, .facts = facts,
                      .probe = {.poses = poses, .analysis = analyzed ? &analysis : NULL, .batch = batch},
                      .needed_later = needed_later};
    if (poses && fresh) pose_cache_clear(poses); /* another clip's times */
    if (poses && !fresh && analyzed) palette_keep_analysis(poses, &analysis, common_rates[0], clip->loop); /* for the bake */
    return choose_clip(&cs, &f, rows, max_error, c, err);
}

static pose_cache *search_pose_cache(const cb_sampler *s, pose_arena *arena)
{
    return palette_probe_poses(arena, cb_sampler_model(s)->skins[cb_sampler_skin(s)].joint_count, SEARCH_CLIP_POSE_BYTES);
}

void palette_seed_analysis(search_keep *keep, uint32_t i, const cb_sampler *s, const cb_clip_info *analysis, double fps,
                           int loop)
{
    if (keep && !keep->poses[i]) keep->poses[i] = search_pose_cache(s, keep->arena);
    if (keep && keep->poses[i]) palette_keep_analysis(keep->poses[i], analysis, fps, loop);
}

double cb_choose_clip_fps(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *clip, double max_error,
                          double max_fps, bool *met, double *error, cb_error *err)
{
    palette_skin_facts facts;
    pose_cache *poses = search_pose_cache(s, NULL); /* NULL (out of memory): sampled as without */
    pose_batch *batch = pose_batch_create(s); /* NULL (out of memory): poses sampled one at a time */
    double fps = max_fps;
    cb_rate_choice c = {0};
    c.error = INFINITY;
    if (!palette_skin_facts_build(s, &facts, err))
        fps = choose_clip_fps(s, o, clip, max_error, max_fps, o->fit || clip->fit ? CB_ROWS_FITTED : CB_ROWS_SAMPLED, &c,
                              &facts, poses, true, batch, false, err);
    palette_skin_facts_free(&facts);
    pose_cache_free(poses);
    pose_batch_free(batch);
    *met = c.met, *error = err->status ? INFINITY : c.error;
    return fps;
}

/* Clips are searched independently: options->threads at a time, each thread with its own
 * sampler (a sampler's scratch is not shared), each clip's answer in its own slot, so the
 * choices do not depend on the thread count nor on the order clips are taken in: the clips
 * with the most work first (search_order), so that no long clip starts last and leaves the
 * other threads waiting (Cow: Eating lasts 6 s, the other clips 0.6-3.3 s). A job's work beside
 * the search (search_beside: the speed reference, travels) is taken by the first thread to find the
 * searches it reads over; those clips go first. */
typedef struct rate_search {
    const cb_model *model;
    int32_t skin;
    const cb_bake_options *o;
    cb_clip_plan *plan;
    uint32_t count;
    const cb_rate_goal *goals;
    cb_rate_choice *choices;
    cb_error *errors; /* per clip */
    double height;
    const palette_skin_facts *facts;
    const uint32_t *order; /* the clips in the order they are taken */
    atomic_uint next;
    pose_cache **kept;     /* per clip, or NULL: the poses each clip's search sampled, for the bake after */
    pose_arena *arena;     /* what kept's blocks come from, or NULL */
    atomic_size_t kept_bytes;
    const bool *needed_later; /* per clip, or NULL: clips whose caller searches on where they miss */
    search_beside *beside;    /* the keep's work beside the search, not taken yet, or NULL */
    const search_keep *keep;
    atomic_uint unread;       /* the searches it reads not over yet */
} rate_search;

/* The cache clip i's search samples into: the thread's own (`mine`, emptied for each clip), or,
 * when the caller keeps them, the clip's own. */
static pose_cache *clip_cache(rate_search *rs, uint32_t i, pose_cache *mine, const cb_sampler *s)
{
    if (!rs->kept) return mine;
    if (!rs->kept[i]) rs->kept[i] = search_pose_cache(s, rs->arena);
    return rs->kept[i];
}

/* The highest rate the search may probe a clip at: its goal's, checked by palette_choose_rates
 * (a bake's is resolved once, cb_resolve_clip_settings). */
static double max_fps_of(const cb_rate_goal *goal) { return goal->max_fps; }

/* The clips' expected work: their rows at the highest rate a probe may bake them at. */
static double search_work(const cb_model *m, const cb_clip_plan *plan, const cb_rate_goal *goal)
{
    if (plan->animation < 0 || plan->animation >= (int32_t)m->animation_count) return 0; /* fails at once */
    const cb_animation *a = &m->animations[plan->animation];
    return (a->t1 - a->t0) * max_fps_of(goal);
}

/* Whether clip a is searched before clip b (a < b), by search_order. */
static bool searched_before(const cb_model *m, const cb_clip_plan *plan, const cb_rate_goal *goals, const bool *first,
                            uint32_t a, uint32_t b)
{
    bool lead_a = first && first[a], lead_b = first && first[b];
    return lead_a != lead_b ? lead_a : search_work(m, &plan[a], &goals[a]) >= search_work(m, &plan[b], &goals[b]);
}

/* The clips in decreasing expected work (ties in clip order), into order; those the work beside
 * the search reads (first[i], NULL: none) before the others, so that it is ready while clips are
 * left for the other threads (else the last of them would wait for it). */
static void search_order(const cb_model *m, const cb_clip_plan *plan, const cb_rate_goal *goals, const bool *first,
                         uint32_t count, uint32_t *order)
{
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t k = i;
        for (; k > 0 && !searched_before(m, plan, goals, first, order[k - 1], i); --k) order[k] = order[k - 1];
        order[k] = i;
    }
}

/* Clip i's search on the thread's sampler s (NULL: it failed, with `fail`), its own cache or the
 * thread's (poses) and the thread's batches. */
static void search_clip(rate_search *rs, uint32_t i, cb_sampler *s, const cb_error *fail, pose_cache *poses,
                        pose_batch *batch)
{
    if (!(rs->goals[i].max_error_mm > 0)) return;
    if (!s) {
        rs->errors[i] = *fail;
        return;
    }
    cb_rate_choice *c = &rs->choices[i];
    if (rs->kept) cb_clip_plan_release(&rs->plan[i]); /* a job's earlier search's timed rows (its plan's own) */
    rs->plan[i].fps = choose_clip_fps(s, rs->o, &rs->plan[i], rs->goals[i].max_error_mm / 1000 * rs->height,
                                      max_fps_of(&rs->goals[i]), rs->o->fit ? CB_ROWS_FITTED : rs->goals[i].rows, c,
                                      rs->facts, clip_cache(rs, i, poses, s), !rs->kept, batch,
                                      rs->needed_later && rs->needed_later[i], &rs->errors[i]);
    rs->plan[i].fit = c->fitted;
    c->error_mm = cb_mm_per_m(c->error, rs->height);
    if (rs->kept && !rs->errors[i].status && global_timed_asked(rs->o, &rs->plan[i])) /* rows on its keys, asked for */
        global_clip_timed(s, rs->o, &rs->plan[i], rs->facts, rs->kept[i], rs->goals[i].max_error_mm / 1000 * rs->height, c,
                          &rs->errors[i]);
    if (rs->kept) /* few of its poses read again: palette_bake.h */
        search_keep_settle(&rs->kept[i], rs->model->skins[rs->skin].joint_count, &rs->kept_bytes, true);
}

/* The work beside the search, run by the first thread to find the searches it reads over
 * (acquire: their threads' release of `unread` made them visible here). */
static void take_beside(rate_search *rs)
{
    if (rs->beside && atomic_load_explicit(&rs->unread, memory_order_acquire) == 0 &&
        !atomic_exchange(&rs->beside->taken, true))
        rs->beside->run(rs->beside, rs->keep);
}

static int rate_worker(void *arg)
{
    rate_search *rs = arg;
    cb_error fail = {0};
    cb_sampler *s = cb_sampler_create(rs->model, rs->skin, &fail);
    pose_cache *poses = s && !rs->kept ? search_pose_cache(s, NULL) : NULL; /* this thread's, for each clip in turn */
    pose_batch *batch = s ? pose_batch_create(s) : NULL; /* this thread's batches of poses (NULL: one at a time) */
    for (;;) {
        take_beside(rs);
        uint32_t n = atomic_fetch_add(&rs->next, 1);
        if (n >= rs->count) break;
        uint32_t i = rs->order[n];
        search_clip(rs, i, s, &fail, poses, batch);
        if (rs->beside && rs->beside->reads && rs->beside->reads[i])
            atomic_fetch_sub_explicit(&rs->unread, 1, memory_order_release);
    }
    pose_cache_free(poses);
    pose_batch_free(batch);
    cb_sampler_free(s);
    return 0;
}

cb_status cb_choose_rates(cb_sampler *s, const cb_bake_options *o, cb_clip_plan *plan, uint32_t count,
                          const cb_rate_goal *goals, cb_rate_choice *out, cb_error *err)
{
    return palette_choose_rates(s, o, plan, count, goals, out, NULL, NULL, err);
}

cb_status palette_choose_rates(cb_sampler *s, const cb_bake_options *o, cb_clip_plan *plan, uint32_t count,
                               const cb_rate_goal *goals, cb_rate_choice *out, search_keep *keep,
                               const bool *needed_later, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    bool any = false;
    for (uint32_t i = 0; i < count; ++i) any = any || goals[i].max_error_mm > 0;
    if (!any) return CB_OK;
    for (uint32_t i = 0; i < count; ++i)
        if (goals[i].max_error_mm > 0 && !(goals[i].max_fps >= 2 && goals[i].max_fps <= CB_FPS_LIMIT))
            return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_MAX_FPS, "%s: clip %u's rate search goes up to max_fps "
                                   "%g; give it 2..%g (a bake's default: %g)", m->source, i, goals[i].max_fps,
                                   CB_FPS_LIMIT, CB_AUTO_MAX_FPS);
    palette_skin_facts own;
    const palette_skin_facts *facts = search_keep_facts(keep, s, &own, err);
    if (!facts) return err->status;
    if (!(facts->height > 0)) {
        palette_skin_facts_free(&own);
        return cb_fail(err, CB_ERR_INPUT, "%s: has no skinned mesh to measure errors on; give the clips a fixed fps",
                       m->source);
    }
    if (o->bone_space == CB_BONE_SPACE_LOCAL) /* its key rate's multiples, measured composed (local_rate.c) */
        return local_choose_rates(s, o, plan, count, goals, out, keep, facts, needed_later, err), palette_skin_facts_free(&own),
               err->status;
    rate_search rs = {m, cb_sampler_skin(s), o, plan, count, goals, calloc(count, sizeof(cb_rate_choice)),
                      calloc(count, sizeof(cb_error)), facts->height, facts, NULL, 0, keep ? keep->poses : NULL,
                      keep ? keep->arena : NULL, 0, needed_later, NULL, keep, 0};
    uint32_t *order = malloc(count * sizeof *order);
    rs.order = order;
    if (keep && keep->beside && !atomic_load(&keep->beside->taken) && count == keep->count) { /* (not done yet) */
        rs.beside = keep->beside;
        for (uint32_t i = 0; rs.beside->reads && i < count; ++i) rs.unread += rs.beside->reads[i];
    }
    if (rs.choices && rs.errors && order) {
        search_order(m, plan, goals, rs.beside ? rs.beside->reads : NULL, count, order);
        uint32_t threads = o->threads < 1 ? 1 : o->threads > 64 ? 64 : o->threads, started = 0;
        if (threads > count) threads = count;
        thrd_t ids[64];
        for (uint32_t t = 1; t < threads; ++t)
            if (thrd_create(&ids[started], rate_worker, &rs) == thrd_success) ++started;
        rate_worker(&rs);
        for (uint32_t t = 0; t < started; ++t) thrd_join(ids[t], NULL);
        for (uint32_t i = 0; i < count && !err->status; ++i) /* the first failure in clip order */
            if (rs.errors[i].status) *err = rs.errors[i];
        for (uint32_t i = 0; out && i < count; ++i)
            if (goals[i].max_error_mm > 0) out[i] = rs.choices[i];
    } else {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory choosing frame rates for %s", m->source);
    }
    free(rs.choices), free(rs.errors), free(order);
    palette_skin_facts_free(&own);
    return err->status;
}
