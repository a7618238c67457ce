/* palette_plan.c - what a bake settles before sampling: every clip's frames and rows, the
 * texture's geometry (rows wrapped into column blocks), the bind positions and the padding. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/budget.h"
#include "clip_memo.h"
#include "palette_bake.h"
#include "pool.h"

/* ---- geometry of the texture ---- */

cb_status palette_plan_texture(cb_palette *p, uint32_t max_size, const char *source, cb_error *err)
{
    if (max_size < 1) return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_MAX_TEXTURE_SIZE, "the texture size limit must be at least 1");
    if (p->row_texels > max_size)
        return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_TEXTURE_SIZE,
                               "%s: %u bones x %u texels = %u texels per row, wider than the texture size limit %u; use "
                               "a layout with fewer texels per bone (qpos: 2) or a larger limit",
                       source, p->bone_count, p->texels_per_bone, p->row_texels, max_size);
    cb_texture_geometry g;
    if (!cb_wrap_rows(p->row_texels, p->rows, max_size, &g))
        return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_TEXTURE_SIZE,
                               "%s: %u baked rows do not fit a %ux%u texture even wrapped into %u columns of %u rows; "
                               "lower the fps, bake fewer clips, or raise the texture size limit",
                       source, p->rows, max_size, max_size, max_size / p->row_texels, max_size);
    p->blocks = g.blocks, p->height = g.height, p->width = g.width;
    return CB_OK;
}

/* ---- framing the clips ---- */

/* The analyses of a plan's clips, shared out over threads: each animation's first clip, on a
 * sampler of each thread's own. A later clip of the same animation (a loop and a one-shot of
 * it) is analyzed after, in order, on the caller's sampler, which by then holds the period the
 * earlier one set, as analyzing them all in order would. */
typedef struct analyses {
    const bake_state *st;
    const cb_clip_plan *plan; /* or NULL: every animation */
    uint32_t count;
    cb_clip_info *infos;
    cb_error *errors;         /* per clip */
    bool *first_use;          /* per clip: the first of its animation */
    bool *done;               /* per clip: analyzed by a share */
    atomic_uint next;
} analyses;

static cb_clip_plan plan_entry(const cb_clip_plan *plan, uint32_t i)
{
    return plan ? plan[i] : (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL};
}

static void analyze_share(void *arg, uint32_t thread, uint32_t threads)
{
    (void)thread, (void)threads;
    analyses *a = arg;
    cb_error ignored = {0};
    cb_sampler *s = cb_sampler_create(a->st->model, a->st->skin, &ignored);
    for (uint32_t i = atomic_fetch_add(&a->next, 1); s && i < a->count; i = atomic_fetch_add(&a->next, 1)) {
        if (!a->first_use[i]) continue;
        cb_clip_plan one = plan_entry(a->plan, i);
        cb_clip_analyze(s, one.animation, cb_clip_plan_fps(&one, a->st->opt->fps), one.loop, &a->st->opt->limits,
                        &a->infos[i], &a->errors[i]);
        a->done[i] = true;
    }
    cb_sampler_free(s); /* a share without a sampler leaves its clips to the caller */
}

/* ---- a rate search's analyses, framed again ---- */

typedef struct kept_analysis {
    cb_clip_info info; /* as cb_clip_analyze gave it at `fps` */
    double fps;
    int loop;          /* the loop override it was analyzed with */
} kept_analysis;

void palette_keep_analysis(pose_cache *poses, const cb_clip_info *analysis, double fps, int loop)
{
    kept_analysis *k = malloc(sizeof *k);
    if (k) *k = (kept_analysis){*analysis, fps, loop};
    pose_cache_attach_analysis(poses, k); /* NULL: none (the bake analyzes the clip) */
}

/* Clip i's analysis from its rate search (kept with its poses), framed at the bake's rate, into
 * *out: what analyzing it at that rate gives (cb_clip_analyze depends on its rate through its
 * framing and feet_weighed_alike alone), so the bake after a search (Husky: 21 M instructions)
 * does not analyze its clips again. Only for a clip whose animation no other clip of the plan
 * bakes (analyze_clips orders those); false where none is kept or it cannot stand in, and then
 * the clip is analyzed. err: the framing's failure, as analyzing would end with it. */
static bool take_analysis(const bake_state *st, const cb_clip_plan *plan, uint32_t count, uint32_t i,
                          cb_clip_info *out, cb_error *err)
{
    cb_clip_plan one = plan_entry(plan, i);
    pose_cache *poses = plan && st->clip_poses ? st->clip_poses[i] : NULL;
    double fps = cb_clip_plan_fps(&one, st->opt->fps);
    if (!poses || !palette_kept_analysis(poses, one.animation, one.loop, fps, &st->opt->limits)) return false;
    for (uint32_t c = 0; c < count; ++c)
        if (c != i && plan_entry(plan, c).animation == one.animation) return false;
    *out = ((const kept_analysis *)pose_cache_analysis(poses))->info;
    cb_clip_frame_at(st->model, fps, &st->opt->limits, out, err);
    return true;
}

bool palette_kept_analysis(const pose_cache *poses, int32_t animation, int loop, double fps, const cb_limits *limits)
{
    const kept_analysis *k = pose_cache_analysis(poses);
    return k && k->loop == loop && k->info.animation == animation && clip_feet_weighed_alike(&k->info, k->fps, fps, limits);
}

void palette_memo_keep_search(struct clip_memo *memo, const cb_sampler *sampler, const pose_cache *poses,
                              const cb_limits *limits)
{
    const kept_analysis *k = poses ? pose_cache_analysis(poses) : NULL;
    if (k) clip_memo_keep(memo, sampler, &k->info, k->fps, k->loop, limits);
}

const cb_clip_info *palette_kept_analysis_info(const pose_cache *poses)
{
    const kept_analysis *k = poses ? pose_cache_analysis(poses) : NULL;
    return k ? &k->info : NULL;
}

bool palette_take_kept_analysis(const pose_cache *poses, cb_sampler *sampler, int32_t animation, int loop, double fps,
                                const cb_limits *limits, cb_clip_info *out)
{
    cb_error ignored = {0};
    if (!palette_kept_analysis(poses, animation, loop, fps, limits)) return false;
    *out = ((const kept_analysis *)pose_cache_analysis(poses))->info;
    /* As analyzing it ends: framed at fps, the clip's loop set on the sampler. */
    return !cb_clip_frame_at(cb_sampler_model(sampler), fps, limits, out, &ignored) && cb_sampler_set_loop(sampler, out);
}

/* Clip i's analysis from the run's memo (an earlier analysis of the bake standing in), framed
 * at the bake's rate, its loop set on the caller's sampler: true where the memo had one. */
static bool take_memo(const bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t i, cb_clip_info *out)
{
    cb_clip_plan one = plan_entry(plan, i);
    return clip_memo_take(st->memo, sampler, one.animation, cb_clip_plan_fps(&one, st->opt->fps), one.loop,
                          &st->opt->limits, out);
}

/* The clips' analyses into infos, on opt->threads threads where there are clips to share (or
 * from their rate searches, take_analysis). */
static cb_status analyze_clips(const bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t count,
                               cb_clip_info *infos, cb_error *err)
{
    const cb_model *m = st->model;
    size_t n = count ? count : 1;
    analyses a = {st, plan, count, infos, calloc(n, sizeof(cb_error)), calloc(n, sizeof(bool)), calloc(n, sizeof(bool)), 0};
    cb_status rc = a.errors && a.first_use && a.done ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint32_t threads = st->opt->threads < count ? st->opt->threads : count;
    for (uint32_t i = 0; !rc && i < count; ++i) a.done[i] = take_analysis(st, plan, count, i, &infos[i], &a.errors[i]);
    for (uint32_t i = 0; !rc && i < count; ++i) a.done[i] = a.done[i] || take_memo(st, sampler, plan, i, &infos[i]);
    for (uint32_t i = 0; !rc && threads > 1 && i < count; ++i) {
        int32_t anim = plan_entry(plan, i).animation;
        a.first_use[i] = anim >= 0 && anim < (int32_t)m->animation_count && !a.done[i];
        for (uint32_t k = 0; a.first_use[i] && k < i; ++k) a.first_use[i] = plan_entry(plan, k).animation != anim;
    }
    if (!rc && threads > 1) cb_pool_run(threads, analyze_share, &a);
    for (uint32_t i = 0; !rc && i < count; ++i) {
        cb_clip_plan one = plan_entry(plan, i);
        if (!a.done[i])
            rc = cb_clip_analyze(sampler, one.animation, cb_clip_plan_fps(&one, st->opt->fps), one.loop, &st->opt->limits,
                                 &infos[i], err);
        else if (a.errors[i].status)
            *err = a.errors[i], rc = err->status;
        else if (!cb_sampler_set_loop(sampler, &infos[i])) /* as analyzing it here */
            rc = cb_fail(err, CB_ERR_INTERNAL, "out of memory closing the loop of clip '%s'", m->animations[one.animation].name);
        if (!rc) clip_memo_keep(st->memo, sampler, &infos[i], cb_clip_plan_fps(&one, st->opt->fps), one.loop, &st->opt->limits);
    }
    free(a.errors), free(a.first_use), free(a.done);
    return rc;
}

cb_status palette_frame_clips(bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t count,
                             cb_clip_info **infos_out, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_model *m = st->model;
    if (!plan) count = m->animation_count;
    cb_clip_info *infos = calloc(count ? count : 1, sizeof *infos);
    p->clips = calloc(count ? count : 1, sizeof *p->clips);
    *infos_out = infos;
    if (!infos || !p->clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (st->analysis) {
        infos[0] = *st->analysis; /* framed at this bake's rate, not analyzed again */
        if (cb_clip_frame_at(m, cb_clip_plan_fps(&plan[0], st->opt->fps), &st->opt->limits, &infos[0], err))
            return err->status;
    } else if (analyze_clips(st, sampler, plan, count, infos, err)) {
        return err->status;
    }
    uint64_t rows = 0;
    for (uint32_t i = 0; i < count; ++i) {
        cb_clip_plan one = plan_entry(plan, i);
        cb_palette_clip *c = &p->clips[i];
        c->name = one.name ? one.name : m->animations[one.animation].name;
        c->first_row = (uint32_t)rows;
        c->frames = infos[i].frames;
        c->fps = infos[i].effective_fps;
        c->duration = infos[i].duration;
        c->start = infos[i].t0;
        c->loops = infos[i].loops;
        c->ground_speed = infos[i].ground_speed;
        c->fitted = (st->opt->fit || one.fit) && !one.step;
        c->step = one.step;
        for (int k = 0; k < 3; ++k)
            c->root_velocity[k] = (float)(cb_root_motion_in_place(st->opt->root_motion, &infos[i]) ? infos[i].root_velocity[k] : 0);
        rows += infos[i].frames;
        if (rows > st->opt->limits.max_frames)
            return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_FRAMES, "%s: %llu baked rows over all clips, over the limit of %u",
                           m->source, (unsigned long long)rows, st->opt->limits.max_frames);
    }
    p->clip_count = count;
    p->rows = (uint32_t)rows;
    return CB_OK;
}

void palette_bind_positions(const cb_skin *skin, float *bind)
{
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        /* The joint's bind-pose position is the translation of inverse(IBM). */
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        double det = cb_mat4_determinant3(ibm);
        cb_vec3 b = {0, 0, 0};
        if (fabs(det) > 1e-300) {
            /* Solve A b = -t with Cramer's rule. */
            double t[3] = {-ibm[12], -ibm[13], -ibm[14]}, col[16];
            double *res[3] = {&b.x, &b.y, &b.z};
            for (int k = 0; k < 3; ++k) {
                memcpy(col, ibm, sizeof col);
                col[k * 4 + 0] = t[0], col[k * 4 + 1] = t[1], col[k * 4 + 2] = t[2];
                *res[k] = cb_mat4_determinant3(col) / det;
            }
        }
        bind[j * 3] = (float)b.x, bind[j * 3 + 1] = (float)b.y, bind[j * 3 + 2] = (float)b.z;
    }
}

/* ---- the skin's facts ---- */

cb_status palette_skin_facts_build(cb_sampler *sampler, palette_skin_facts *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(sampler);
    int32_t skin = cb_sampler_skin(sampler);
    uint32_t bones = m->skins[skin].joint_count;
    double lo[3], hi[3];
    memset(out, 0, sizeof *out);
    out->bind_positions = malloc((bones ? bones : 1) * 3 * sizeof(float));
    out->reach = malloc((bones ? bones : 1) * sizeof(double));
    if (!out->bind_positions || !out->reach)
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory measuring the palette's error", m->source);
    palette_bind_positions(&m->skins[skin], out->bind_positions);
    out->skinned = palette_joint_reach(out->bind_positions, bones, m, skin, out->reach);
    out->group_reach = calloc(bones ? bones : 1, sizeof(double));
    if (!out->group_reach || (out->skinned && !cb_vertex_groups_build(m, skin, out->bind_positions, &out->groups)))
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory measuring the palette's error", m->source);
    for (uint32_t k = 0; k < out->groups.group_count; ++k) {
        const cb_vertex_group *grp = &out->groups.groups[k];
        out->weight_sum = grp->weight_sum > out->weight_sum ? grp->weight_sum : out->weight_sum;
        for (uint32_t i = 0; i < grp->joint_count; ++i) {
            const cb_group_joint *gj = &out->groups.joints[grp->joint_first + i];
            if (gj->reach > out->group_reach[gj->joint]) out->group_reach[gj->joint] = gj->reach;
        }
    }
    out->height = cb_skin_rest_bounds(sampler, lo, hi);
    return CB_OK;
}

void palette_skin_facts_free(palette_skin_facts *f)
{
    free(f->bind_positions), free(f->reach), free(f->group_reach), cb_vertex_groups_free(&f->groups);
    memset(f, 0, sizeof *f);
}

search_keep *search_keep_create(uint32_t n)
{
    search_keep *keep = calloc(1, sizeof *keep + (n ? n : 1) * sizeof(pose_cache *));
    if (keep) keep->count = n, keep->arena = pose_arena_create(); /* NULL: each cache its own blocks */
    return keep;
}

void search_keep_free(search_keep *keep)
{
    for (uint32_t i = 0; keep && i < keep->count; ++i) pose_cache_free(keep->poses[i]);
    if (keep) pose_arena_free(keep->arena);
    if (keep && keep->beside) keep->beside->release(keep->beside);
    if (keep && keep->has_facts) palette_skin_facts_free(&keep->facts);
    free(keep);
}

void search_keep_settle(pose_cache **cache, uint32_t bones, atomic_size_t *kept_bytes, bool release_poses)
{
    if (!*cache) return;
    size_t bytes = (size_t)pose_cache_count(*cache) * (16 * bones + 1 + 5 * bones) * sizeof(double);
    if (atomic_fetch_add(kept_bytes, bytes) + bytes > SEARCH_KEPT_POSE_BYTES) pose_cache_free(*cache), *cache = NULL;
    else if (release_poses) pose_cache_release_poses(*cache);
}

const palette_skin_facts *search_kept_facts(const search_keep *keep, const cb_sampler *sampler)
{
    bool same = keep && keep->has_facts && keep->model == cb_sampler_model(sampler) && keep->skin == cb_sampler_skin(sampler);
    return same ? &keep->facts : NULL;
}

const palette_skin_facts *search_keep_facts(search_keep *keep, cb_sampler *sampler, palette_skin_facts *own,
                                            cb_error *err)
{
    memset(own, 0, sizeof *own);
    const palette_skin_facts *kept = search_kept_facts(keep, sampler);
    if (kept) return kept;
    bool keeps = keep && !keep->has_facts; /* the first search of the job settles them for the rest */
    palette_skin_facts *into = keeps ? &keep->facts : own;
    if (palette_skin_facts_build(sampler, into, err)) return palette_skin_facts_free(into), NULL;
    if (keeps) keep->has_facts = true, keep->model = cb_sampler_model(sampler), keep->skin = cb_sampler_skin(sampler);
    return into;
}

/* The texels no row covers, which stay zero: in the last block the rows past the last baked
 * one. (Every row's texels are written by the encoder.) */
void palette_zero_padding(cb_palette *p)
{
    size_t tb = cb_precision_texel_bytes(p->precision);
    unsigned char *texels = p->texels;
    for (uint32_t y = 0; y < p->height; ++y) {
        uint32_t blocks_here = p->rows / p->height + (y < p->rows % p->height);
        size_t x0 = (size_t)blocks_here * p->row_texels;
        if (x0 < p->width) memset(texels + ((size_t)y * p->width + x0) * tb, 0, (p->width - x0) * tb);
    }
}
