/* plant_keys.c - one clip's planted feet as new keys of its leg chains (plant_feet.h).
 *
 * A planted foot stays where it landed in a world the body crosses at the clip's ground speed
 * v along its heading d (stride.h's frame: the root's average travel taken off, as an in-place
 * bake stores it). At each key of the clip every planted foot's sole is pulled back there by
 * turning the leg's two bones above the foot (leg_ik.h); the foot bone keeps its orientation in
 * the world, and rig bones outside the chain that carry the sole (an IK control the paw is
 * weighted to) move with it. A paw weighted to such a bone alone is reached with the leg's two
 * long bones and the shin's tip. The pull fades in before the landing and out after the lift.
 * New keys go at the clip's own key times (its densest channel's), so its key step, span and
 * loop framing stay.
 *
 * The hold: a foot is held fully a little before it lands and after it lifts. The bake's rows
 * sample the clip at about 30 fps and a runtime blends between them, so a foot pulled only from
 * its landing on moves, over the row interval that holds the landing, at a blend of its swing and
 * its stance: the worst moment of its slide (Husky's Walk 98%, Cow's Gallop 80%, through the C
 * reader). Held from one such interval before, it comes down onto its place. */
#include "plant_feet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/stride.h"
#include "../core/foot_sole.h"
#include "../core/leg_ik.h"
#include "../core/sampler.h" /* the local transforms a sample leaves (local_trs) */

enum { MAX_CARRIED = 4, MEAN_SAMPLES = 32 };


typedef struct leg {
    uint32_t foot;                   /* index into the stride's feet and the soles */
    int32_t hip, knee, ankle;        /* nodes */
    int32_t carried[MAX_CARRIED];    /* nodes outside the chain that carry the sole */
    uint32_t carried_count;
    double ramp, hold;               /* seconds */
    double knee_source, knee_planted; /* the knee's angle at the last key solved, degrees */
    double at[CB_MAX_STANCES][2];    /* where each stance stays, world x z */
} leg;

typedef struct plant_ctx {
    cb_sampler *s;
    const cb_model *m;
    const cb_clip_info *clip;
    const cb_stride *st;
    const foot_sole *soles;
    double *mats;       /* joint matrices, scratch */
    plant_timing timing;
} plant_ctx;

bool plant_owned_add(plant_owned *o, void *p)
{
    if (!p) return false;
    if (o->count == o->cap) {
        void **grown = realloc(o->ptr, (o->cap = o->cap ? o->cap * 2 : 16) * sizeof *grown);
        if (!grown) return free(p), false;
        o->ptr = grown;
    }
    o->ptr[o->count++] = p;
    return true;
}

/* Whether `anc` is `node` or one of its ancestors. */
static bool hangs_from(const cb_model *m, int32_t node, int32_t anc)
{
    for (int32_t n = node; n >= 0; n = m->nodes[n].parent)
        if (n == anc) return true;
    return false;
}

static bool under_control(const cb_model *m, int32_t node)
{
    for (int32_t n = node; n >= 0; n = m->nodes[n].parent)
        if (rig_name_is_control(m->nodes[n].name)) return true;
    return false;
}

static bool is_joint(const cb_skin *sk, int32_t node)
{
    for (uint32_t j = 0; j < sk->joint_count; ++j)
        if (sk->joints[j] == node) return true;
    return false;
}

/* Whether a joint can end a leg chain: its parent and grandparent are joints, and no rig control
 * moves it. */
static bool chain_end(const cb_model *m, const cb_skin *sk, int32_t node, int32_t *knee, int32_t *hip)
{
    *knee = m->nodes[node].parent, *hip = *knee >= 0 ? m->nodes[*knee].parent : -1;
    return *hip >= 0 && is_joint(sk, *knee) && is_joint(sk, *hip) && !under_control(m, node);
}

static int32_t first_child(const cb_model *m, int32_t node)
{
    for (uint32_t i = 0; i < m->node_count; ++i)
        if (m->nodes[i].parent == node) return (int32_t)i;
    return -1;
}

/* Distance from p to a bone: from its joint to its first child node. */
static double bone_distance(const cb_model *m, const double *g, int32_t node, cb_vec3 p)
{
    int32_t tip = first_child(m, node);
    cb_vec3 a = {g[node * 16 + 12], g[node * 16 + 13], g[node * 16 + 14]};
    cb_vec3 b = {g[tip * 16 + 12], g[tip * 16 + 13], g[tip * 16 + 14]};
    cb_vec3 ab = cb_vec3_sub(b, a), ap = cb_vec3_sub(p, a);
    double len2 = cb_vec3_dot(ab, ab), x = len2 > 0 ? cb_vec3_dot(ap, ab) / len2 : 0;
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    return cb_vec3_length(cb_vec3_sub(ap, cb_vec3_scale(ab, x)));
}

/* The leg's last bone when no joint of a chain carries the sole (Husky's front paws are weighted
 * to an IK bone alone): the chain-ending deform bone that passes nearest the sole at rest. */
static int32_t nearest_chain_end(const plant_ctx *c, const foot_sole *sole, const bool *deforms)
{
    const cb_skin *sk = &c->m->skins[cb_sampler_skin(c->s)];
    double h, xz[2], best = INFINITY;
    cb_sample_joint_matrices(c->s, -1, 0, c->mats);
    foot_sole_at(sole, c->mats, &h, xz);
    const double *g = cb_sample_globals(c->s, -1, 0);
    int32_t found = -1;
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        int32_t node = sk->joints[j], parent = c->m->nodes[node].parent;
        bool bone = deforms[j] && parent >= 0 && is_joint(sk, parent) && !under_control(c->m, node) &&
                    first_child(c->m, node) >= 0;
        double d = bone ? bone_distance(c->m, g, node, (cb_vec3){xz[0], h, xz[1]}) : INFINITY;
        if (d < best) best = d, found = sk->joints[j];
    }
    return found;
}

/* The leg a sole hangs from: of the joints carrying its weight, the heaviest that ends a chain
 * (else the chain-ending bone nearest the sole); the other joints carrying it, the topmost of
 * each branch, move with its foot. False when there is no chain. */
static bool find_leg(const plant_ctx *c, const foot_sole *sole, leg *out)
{
    const cb_skin *sk = &c->m->skins[cb_sampler_skin(c->s)];
    double *w = calloc(sk->joint_count, sizeof *w), top = 0;
    bool *deforms = malloc(sk->joint_count * sizeof *deforms);
    if (!w || !deforms) return free(w), free(deforms), false;
    rig_deforming_joints(c->m, cb_sampler_skin(c->s), deforms);
    for (uint32_t i = 0; i < sole->count; ++i)
        for (int k = 0; k < 4; ++k)
            if (sole->v[i].joint[k] < sk->joint_count) w[sole->v[i].joint[k]] += sole->v[i].weight[k];
    out->ankle = -1;
    for (uint32_t j = 0; j < sk->joint_count; ++j)
        if (w[j] > top && chain_end(c->m, sk, sk->joints[j], &out->knee, &out->hip)) top = w[j], out->ankle = sk->joints[j];
    if (out->ankle >= 0) chain_end(c->m, sk, out->ankle, &out->knee, &out->hip);
    else if ((out->knee = nearest_chain_end(c, sole, deforms)) >= 0) /* reach with its tip */
        out->hip = c->m->nodes[out->knee].parent, out->ankle = first_child(c->m, out->knee);
    out->carried_count = 0;
    for (uint32_t j = 0; out->ankle >= 0 && j < sk->joint_count; ++j) {
        int32_t node = sk->joints[j];
        if (!(w[j] > 0) || hangs_from(c->m, node, out->ankle) || hangs_from(c->m, out->ankle, node)) continue;
        bool below_other = false; /* a carried bone's child moves with it */
        for (uint32_t i = 0; i < sk->joint_count && !below_other; ++i)
            below_other = i != j && w[i] > 0 && hangs_from(c->m, node, sk->joints[i]) &&
                          !hangs_from(c->m, out->ankle, sk->joints[i]);
        if (!below_other && out->carried_count < MAX_CARRIED) out->carried[out->carried_count++] = node;
    }
    free(w), free(deforms);
    return out->ankle >= 0;
}

/* A foot's sole in the in-place frame at clip time t (0 .. duration), x z. */
static void sole_at(const plant_ctx *c, uint32_t foot, double t, double xz[2])
{
    const cb_clip_info *k = c->clip;
    double h, tau = cb_root_travel_time(t, k->t1 - k->t0, k->duration, k->loops);
    cb_sample_joint_matrices(c->s, k->animation, k->t0 + t, c->mats);
    foot_sole_at(&c->soles[foot], c->mats, &h, xz);
    xz[0] -= k->root_velocity[0] * tau, xz[1] -= k->root_velocity[2] * tau;
}

/* A stance's lift, unwrapped past its landing. */
static double lift_after(const cb_stance *sn, double duration) { return sn->lift >= sn->land ? sn->lift : sn->lift + duration; }

/* Where each stance stays (the mean of where its sole is in the world over the stance: the
 * least change) and the fade, the shortest swing's share. */
static void plan_stances(const plant_ctx *c, leg *l)
{
    const cb_foot *f = &c->st->feet[l->foot];
    double D = c->clip->duration, v = c->st->speed, swing = D;
    for (uint32_t j = 0; j < f->stance_count; ++j) {
        const cb_stance *sn = &f->stances[j];
        double land = sn->land, lift = lift_after(sn, D), sum[2] = {0, 0}, xz[2];
        for (int i = 0; i < MEAN_SAMPLES; ++i) {
            double t = land + (lift - land) * (i + 0.5) / MEAN_SAMPLES;
            sole_at(c, l->foot, fmod(t, D), xz);
            sum[0] += xz[0] + v * c->st->heading[0] * t, sum[1] += xz[1] + v * c->st->heading[2] * t;
        }
        l->at[j][0] = sum[0] / MEAN_SAMPLES, l->at[j][1] = sum[1] / MEAN_SAMPLES;
        const cb_stance *next = &f->stances[(j + 1) % f->stance_count];
        swing = fmin(swing, fmod(next->land - sn->lift + 2 * D, D));
    }
    l->ramp = c->timing.ramp_share * swing, l->hold = fmin(c->timing.hold, 0.25 * swing);
}

static double smooth(double x) { return x * x * (3 - 2 * x); }

/* How far the leg's foot is pulled at clip time t (x z), and how much of it (0: not at all). */
static double pull_at(const plant_ctx *c, const leg *l, double t, double out[2])
{
    const cb_foot *f = &c->st->feet[l->foot];
    double D = c->clip->duration, best = 0, pin = 0;
    uint32_t which = 0;
    for (uint32_t j = 0; j < f->stance_count; ++j) {
        double land = f->stances[j].land - l->hold, len = lift_after(&f->stances[j], D) - f->stances[j].land + 2 * l->hold;
        double since = fmod(t - land + 2 * D, D), w = 0, at = 0; /* time since it landed, in [0, D) */
        if (since <= len) w = 1, at = land + since;
        else if (since - len < l->ramp) w = smooth(1 - (since - len) / l->ramp), at = land + len;
        if (D - since < l->ramp && smooth(1 - (D - since) / l->ramp) > w) w = smooth(1 - (D - since) / l->ramp), at = land;
        if (w > best) best = w, pin = at, which = j;
    }
    if (best <= 0) return 0;
    double xz[2], v = c->st->speed;
    sole_at(c, l->foot, fmod(pin, D), xz);
    out[0] = best * (l->at[which][0] - v * c->st->heading[0] * pin - xz[0]);
    out[1] = best * (l->at[which][1] - v * c->st->heading[2] * pin - xz[1]);
    return best;
}

static cb_quat qconj(cb_quat q) { return (cb_quat){-q.x, -q.y, -q.z, q.w}; }
static cb_vec3 column(const double *g) { return (cb_vec3){g[12], g[13], g[14]}; }

/* The knee's angle between hip and ankle, degrees. */
static double knee_angle(cb_vec3 a, cb_vec3 b, cb_vec3 c)
{
    cb_vec3 u = cb_vec3_sub(a, b), v = cb_vec3_sub(c, b);
    double d = cb_vec3_dot(u, v) / (cb_vec3_length(u) * cb_vec3_length(v));
    return acos(d < -1 ? -1 : d > 1 ? 1 : d) * 57.29577951308232;
}

/* A node's rotation and uniform scale in the world (identity for none). */
static bool world_turn(const double *globals, int32_t node, cb_quat *q, double *scale)
{
    *q = (cb_quat){0, 0, 0, 1}, *scale = 1;
    if (node < 0) return true;
    cb_vec3 t, s;
    if (!cb_mat4_decompose(globals + (size_t)node * 16, &t, q, &s, 1e-3)) return false;
    *scale = s.x;
    return true;
}

/* A local rotation turned by `g` in the world, under a parent turned `parent` in the world:
 * qconj(P) g P L. */
static cb_quat turned(cb_quat parent, cb_quat g, cb_quat local)
{
    return cb_quat_normalize(cb_quat_mul(qconj(parent), cb_quat_mul(g, cb_quat_mul(parent, local))));
}

static cb_quat local_turn(const double *trs) { return (cb_quat){trs[3], trs[4], trs[5], trs[6]}; }

static double angle_between(cb_quat a, cb_quat b)
{
    double d = fabs(cb_quat_dot(a, b));
    return 2 * acos(d < 1 ? d : 1) * 57.29577951308232;
}

/* One key's new leg: rotations of hip, knee, ankle (rot[3]) and the carried bones' local
 * translations (moved[]), from the globals and locals sampled at it. False on shear. */
static bool solve_key(const plant_ctx *c, const leg *l, const double pull[2], const double *g, const double *trs,
                      cb_quat rot[3], cb_vec3 *moved, double *shortfall, double *knee)
{
    cb_vec3 a = column(g + (size_t)l->hip * 16), b = column(g + (size_t)l->knee * 16), k = column(g + (size_t)l->ankle * 16);
    cb_vec3 target = {k.x + pull[0], k.y, k.z + pull[1]}, pole = {c->st->heading[0], 0, c->st->heading[2]};
    cb_quat H, K, wp, wh, wk;
    double sp, sh, sk;
    cb_vec3 reached = leg_ik_solve(a, b, k, target, pole, &H, &K);
    *shortfall = fmax(*shortfall, cb_vec3_length(cb_vec3_sub(target, reached)));
    *knee = knee_angle(a, cb_vec3_add(a, cb_quat_rotate(H, cb_vec3_sub(b, a))), reached);
    if (!world_turn(g, c->m->nodes[l->hip].parent, &wp, &sp) || !world_turn(g, l->hip, &wh, &sh) ||
        !world_turn(g, l->knee, &wk, &sk))
        return false;
    cb_quat KH = cb_quat_normalize(cb_quat_mul(K, H));
    rot[0] = turned(wp, H, local_turn(trs + (size_t)l->hip * 10));
    rot[1] = turned(wh, cb_quat_mul(qconj(H), KH), local_turn(trs + (size_t)l->knee * 10));
    rot[2] = turned(wk, qconj(KH), local_turn(trs + (size_t)l->ankle * 10));
    cb_vec3 step = cb_vec3_sub(reached, k);
    for (uint32_t i = 0; i < l->carried_count; ++i) {
        int32_t n = l->carried[i];
        cb_quat wq;
        double s;
        if (!world_turn(g, c->m->nodes[n].parent, &wq, &s)) return false;
        cb_vec3 local = cb_quat_rotate(qconj(wq), step);
        const double *t = trs + (size_t)n * 10;
        moved[i] = (cb_vec3){t[0] + local.x / s, t[1] + local.y / s, t[2] + local.z / s};
    }
    return true;
}

/* The clip's densest key times: the new keys go there, so the clip's key step and span (which
 * frame it as a loop) stay as they were. */
static const cb_channel *densest(const cb_animation *anim)
{
    const cb_channel *best = NULL;
    for (uint32_t i = 0; i < anim->channel_count; ++i)
        if (!best || anim->channels[i].key_count > best->key_count) best = &anim->channels[i];
    return best && best->key_count >= 2 ? best : NULL;
}

/* Puts a channel into the animation: in place of one on the same node and path, else added. */
static bool put_channel(cb_animation *anim, cb_channel ch, plant_owned *owned)
{
    for (uint32_t i = 0; i < anim->channel_count; ++i)
        if (anim->channels[i].node == ch.node && anim->channels[i].path == ch.path) return anim->channels[i] = ch, true;
    cb_channel *grown = malloc((anim->channel_count + 1) * sizeof *grown);
    if (!plant_owned_add(owned, grown)) return false;
    memcpy(grown, anim->channels, anim->channel_count * sizeof *grown);
    grown[anim->channel_count++] = ch;
    anim->channels = grown;
    return true;
}

/* The keys of one leg over the clip: values[0..2] rotations (4 floats a key), then a
 * translation (3 a key) per carried bone. */
typedef struct leg_keys {
    float *values[3 + MAX_CARRIED];
} leg_keys;

static bool store_key(leg_keys *lk, const leg *l, uint32_t key, const cb_quat rot[3], const cb_vec3 *moved)
{
    for (int r = 0; r < 3; ++r) {
        cb_quat q = rot[r];
        float *v = lk->values[r] + (size_t)key * 4;
        if (key > 0 && q.x * v[-4] + q.y * v[-3] + q.z * v[-2] + q.w * v[-1] < 0) q = (cb_quat){-q.x, -q.y, -q.z, -q.w};
        v[0] = (float)q.x, v[1] = (float)q.y, v[2] = (float)q.z, v[3] = (float)q.w;
    }
    for (uint32_t i = 0; i < l->carried_count; ++i) {
        float *v = lk->values[3 + i] + (size_t)key * 3;
        v[0] = (float)moved[i].x, v[1] = (float)moved[i].y, v[2] = (float)moved[i].z;
    }
    return true;
}

/* Every key of every leg: sampled, pulled, solved, stored. */
/* One leg's knee at a key, as it was and as planted: how far each turned since the last key. */
static void track_knee(leg *l, const double *g, uint32_t key, double planted, plant_knees *knees)
{
    double source = knee_angle(column(g + (size_t)l->hip * 16), column(g + (size_t)l->knee * 16), column(g + (size_t)l->ankle * 16));
    if (planted < 0) planted = source;
    if (key > 0)
        knees->source = fmax(knees->source, fabs(source - l->knee_source)),
        knees->planted = fmax(knees->planted, fabs(planted - l->knee_planted));
    l->knee_source = source, l->knee_planted = planted;
}

static bool solve_keys(plant_ctx *c, const cb_channel *grid, leg *legs, uint32_t n, leg_keys *keys, cb_plant_clip *out,
                       plant_knees *knees)
{
    uint32_t nodes = c->m->node_count;
    double *g = malloc((size_t)nodes * 16 * sizeof *g), *trs = malloc((size_t)nodes * 10 * sizeof *trs);
    double (*pull)[2] = malloc((n ? n : 1) * sizeof *pull), *w = malloc((n ? n : 1) * sizeof *w);
    bool ok = g && trs && pull && w;
    for (uint32_t key = 0; ok && key < grid->key_count; ++key) {
        double t = grid->times[key] - c->clip->t0;
        for (uint32_t i = 0; i < n; ++i) w[i] = pull_at(c, &legs[i], t, pull[i]);
        memcpy(g, cb_sample_globals(c->s, c->clip->animation, grid->times[key]), (size_t)nodes * 16 * sizeof *g);
        memcpy(trs, c->s->local_trs, (size_t)nodes * 10 * sizeof *trs);
        for (uint32_t i = 0; ok && i < n; ++i) {
            const leg *l = &legs[i];
            int32_t chain[3] = {l->hip, l->knee, l->ankle};
            cb_quat rot[3];
            cb_vec3 moved[MAX_CARRIED];
            for (int r = 0; r < 3; ++r) rot[r] = local_turn(trs + (size_t)chain[r] * 10);
            for (uint32_t j = 0; j < l->carried_count; ++j) {
                const double *p = trs + (size_t)l->carried[j] * 10;
                moved[j] = (cb_vec3){p[0], p[1], p[2]};
            }
            double knee = -1; /* unplanted: as it was */
            if (w[i] > 0) ok = solve_key(c, l, pull[i], g, trs, rot, moved, &out->max_shortfall, &knee);
            track_knee(&legs[i], g, key, knee, knees);
            for (int r = 0; ok && r < 3; ++r)
                out->max_rotation_deg = fmax(out->max_rotation_deg, angle_between(rot[r], local_turn(trs + (size_t)chain[r] * 10)));
            if (ok) store_key(&keys[i], l, key, rot, moved);
        }
    }
    free(g), free(trs), free(pull), free(w);
    return ok;
}

/* The new channels into the animation, their arrays owned. */
static bool put_leg(cb_animation *anim, const cb_channel *grid, const leg *l, leg_keys *lk, plant_owned *owned)
{
    int32_t chain[3] = {l->hip, l->knee, l->ankle};
    bool ok = true;
    for (uint32_t r = 0; r < 3 + l->carried_count; ++r) {
        ok = ok && plant_owned_add(owned, lk->values[r]);
        cb_channel ch = {r < 3 ? chain[r] : l->carried[r - 3], r < 3 ? CB_PATH_ROTATION : CB_PATH_TRANSLATION,
                         CB_INTERP_LINEAR, grid->key_count, grid->times, lk->values[r]};
        ok = ok && put_channel(anim, ch, owned);
    }
    return ok;
}

static bool alloc_keys(leg_keys *lk, const leg *l, uint32_t keys)
{
    memset(lk, 0, sizeof *lk);
    bool ok = true;
    for (uint32_t r = 0; r < 3 + l->carried_count; ++r)
        ok = (lk->values[r] = malloc((size_t)keys * (r < 3 ? 4 : 3) * sizeof(float))) && ok;
    return ok;
}

bool plant_clip(cb_sampler *s, const cb_clip_info *clip, const cb_stride *st, plant_timing timing, cb_animation *anim,
                plant_owned *owned, cb_plant_clip *out, plant_knees *knees)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_channel *grid = densest(anim);
    foot_sole soles[CB_MAX_FEET] = {{0}};
    leg legs[CB_MAX_FEET];
    leg_keys keys[CB_MAX_FEET];
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count, n = 0, found = 0;
    double size, *rest = malloc((size_t)bones * 16 * sizeof *rest);
    plant_ctx c = {s, m, clip, st, soles, malloc((size_t)bones * 16 * sizeof(double)), timing};
    *knees = (plant_knees){0, 0};
    bool ok = rest && c.mats && grid;
    if (ok) {
        cb_sample_joint_matrices(s, -1, 0, rest);
        found = foot_soles_find(s, rest, soles, CB_MAX_FEET, &size);
    }
    for (uint32_t k = 0; ok && k < found && k < st->foot_count; ++k) {
        if (!st->feet[k].strides || !st->feet[k].stance_count || soles[k].joint != st->feet[k].joint) continue;
        legs[n] = (leg){.foot = k};
        if (!find_leg(&c, &soles[k], &legs[n])) continue;
        plan_stances(&c, &legs[n]);
        ok = alloc_keys(&keys[n], &legs[n], grid->key_count);
        ++n;
    }
    ok = ok && solve_keys(&c, grid, legs, n, keys, out, knees);
    for (uint32_t i = 0; i < n; ++i) {
        if (ok) ok = put_leg(anim, grid, &legs[i], &keys[i], owned);
        else for (int r = 0; r < 3 + MAX_CARRIED; ++r) free(keys[i].values[r]);
    }
    out->feet = ok ? n : 0;
    foot_soles_free(soles, found);
    free(rest), free(c.mats);
    return ok;
}
