/* cmd_info.c - `crowdbake info MODEL`: what a model holds. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/json.h"
#include "catalog/catalog.h"
#include "roster/roster.h"
#include "crowdbake/bake.h"
#include "crowdbake/herd_slide.h"
#include "cli.h"
#include "internal/plumbing.h"

const char cmd_info_usage[] =
    "usage: crowdbake info MODEL [--json] [--fps N] [--skin NAME|INDEX] [--plant-feet] [-q] [-v]\n\n"
    "Skins, joints, skinned mesh nodes and vertex counts, and per clip: start, duration, keys,\n"
    "interpolation modes, whether it loops and why, frames at --fps (default 30), root velocity and\n"
    "ground speed (root travel and planted feet), and the footsteps: when each foot lands and lifts;\n"
    "the sockets: nodes under a joint that are not joints, where props attach (bone, bind transform).\n"
    "Then, on stderr, the warnings a bake would give (clips it would leave out, and why); -q leaves\n"
    "them out. --plant-feet adds what `bake --plant-feet` would change per clip (feet locked at bake\n"
    "time: the slide before and after, the largest joint rotation change).\n";

typedef struct clip_facts {
    uint64_t keys;
    unsigned interp_mask; /* bit per cb_interp */
    bool analyzed;
    cb_clip_info info;
    cb_ground_speed speed;
    cb_sync_decision sync; /* as a state of this clip alone would play */
    bool in_place;         /* a bare bake takes its root travel out (cb_bake_job_plan's decision) */
    char root_motion[256]; /* why, for a clip whose root travels; else empty */
    cb_row_travel travel;  /* its per-row travel offset at this framing, as a bare bake decides it */
} clip_facts;

/* What a bare bake does with each clip's root travel, and why (cb_bake_job_plan decides it the
 * same way): with a loop that travels, the loops go in place and the one-shots keep theirs. */
static void decide_root_motion(clip_facts *facts, uint32_t n, double height)
{
    bool loop_travels = false;
    for (uint32_t a = 0; a < n; ++a) loop_travels |= facts[a].analyzed && facts[a].info.loops && cb_clip_travels(&facts[a].info, height);
    for (uint32_t a = 0; a < n; ++a) {
        const cb_clip_info *c = &facts[a].info;
        facts[a].in_place = loop_travels && facts[a].analyzed && c->loops;
        if (!facts[a].analyzed || !cb_clip_travels(c, height)) continue;
        if (c->loops)
            snprintf(facts[a].root_motion, sizeof facts[a].root_motion, "in place: it loops and travels %.3g units a loop, "
                     "which its wrap would pull back at any rate; its velocity (%.3g units/s) is recorded for the game to "
                     "move the instance (--root-motion keep keeps the travel)", c->ground_speed * c->duration, c->ground_speed);
        else
            snprintf(facts[a].root_motion, sizeof facts[a].root_motion, "kept: a one-shot keeps its travel (%.3g units), ending "
                     "where it moved (--root-motion in-place takes it out)", c->ground_speed * c->duration);
    }
}

/* Where props attach: the baked skin's sockets (socket.h). */
typedef struct socket_list {
    uint32_t count;
    cb_socket *items;
    char helpers[512]; /* the nodes left out as rig helpers, each after a space */
} socket_list;

/* The nodes under a joint that are rig helpers (cb_socket_is_rig_helper), named after a space each. */
static void list_rig_helpers(cb_sampler *s, const cb_model *m, char *out, size_t size)
{
    size_t n = 0;
    out[0] = '\0';
    for (uint32_t i = 0; i < m->node_count && n < size; ++i)
        if (cb_socket_is_rig_helper(s, (int32_t)i)) {
            int w = snprintf(out + n, size - n, " %s", m->nodes[i].name);
            n += w > 0 ? (size_t)w : 0;
        }
}

static const char *interp_names[] = {"LINEAR", "STEP", "CUBICSPLINE"};

static void interp_list(unsigned mask, char *out, size_t size)
{
    out[0] = '\0';
    for (int i = 0; i < 3; ++i)
        if (mask & (1u << i)) {
            if (out[0]) strncat(out, "+", size - strlen(out) - 1);
            strncat(out, interp_names[i], size - strlen(out) - 1);
        }
}

/* Each clip's per-row travel as a bare bake at this framing decides it (cb_bake_job_row_travel):
 * a job of the default settings, with root motion as decide_root_motion found it. */
static void measure_row_travel(cb_sampler *s, clip_facts *facts, uint32_t n)
{
    cb_bake_job job;
    cb_bake_job_init(&job);
    job.settings = cb_default_bake_settings();
    for (uint32_t a = 0; a < n; ++a) {
        float *offsets = facts[a].analyzed ? malloc((facts[a].info.frames + 1) * sizeof *offsets) : NULL;
        job.settings.root_motion = facts[a].in_place ? CB_ROOT_MOTION_IN_PLACE : CB_ROOT_MOTION_KEEP;
        if (offsets) cb_bake_job_row_travel(&job, s, &facts[a].info, offsets, &facts[a].travel);
        free(offsets);
    }
}

static int gather_clips(const cb_model *m, int skin, double fps, const cb_limits *limits, clip_facts *facts,
                        socket_list *sockets, cb_error *err)
{
    cb_sampler *s = skin >= 0 ? cb_sampler_create(m, skin, err) : NULL;
    if (skin >= 0 && !s) return err->status;
    if (s) sockets->count = cb_find_sockets(s, &sockets->items), list_rig_helpers(s, m, sockets->helpers, sizeof sockets->helpers);
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        const cb_animation *anim = &m->animations[a];
        for (uint32_t c = 0; c < anim->channel_count; ++c) {
            facts[a].keys += anim->channels[c].key_count;
            facts[a].interp_mask |= 1u << anim->channels[c].interp;
        }
        if (s) {
            if (cb_clip_analyze(s, (int32_t)a, fps, -1, limits, &facts[a].info, err)) break;
            facts[a].analyzed = true;
            cb_measure_ground_speed(s, &facts[a].info, &facts[a].speed);
            cb_decide_sync(NULL, anim->name, facts[a].info.loops, &facts[a].speed, false, &facts[a].sync);
        }
    }
    double lo[3], hi[3];
    if (s) decide_root_motion(facts, m->animation_count, cb_skin_rest_bounds(s, lo, hi));
    if (s && !err->status) measure_row_travel(s, facts, m->animation_count);
    cb_sampler_free(s);
    return err->status;
}

/* How far the planted feet slide at the clip's ground speed, foot by foot; whether a herd shows it
 * (herd_slide.h: after the per-row travel a bare bake ships). */
static void print_slide(int w, const cb_stride *st, const cb_row_travel *travel)
{
    cb_herd_slide slide;
    cb_herd_slide_decide(st, travel, &slide);
    printf("  %-*s feet slide %.0f%% of the ground speed (worst %.0f%%):", w, "", 100 * st->slide_mean, 100 * st->slide_worst);
    for (uint32_t k = 0; k < st->foot_count; ++k)
        if (st->feet[k].strides)
            printf(" %s %.0f%%/%.0f%%", st->feet[k].name, 100 * st->feet[k].slide_mean, 100 * st->feet[k].slide_worst);
    printf("%s\n", slide.warn ? " (the asset's feet slide at any rate)" : "");
}

/* When each striding foot lands and lifts (the manifest's contacts). */
static void print_contacts(int w, const cb_stride *st)
{
    printf("  %-*s footsteps (lands-lifts s):", w, "");
    for (uint32_t k = 0; k < st->foot_count; ++k)
        for (uint32_t s = 0; st->feet[k].strides && s < st->feet[k].stance_count; ++s)
            printf(" %s %.3f-%.3f", st->feet[k].name, st->feet[k].stances[s].land, st->feet[k].stances[s].lift);
    printf("\n");
}

static void print_sockets(const cb_model *m, int skin, const socket_list *sockets, const char *helpers)
{
    if (helpers[0]) printf("  not sockets (rig helpers: their joint moves no vertex and is named as a control):%s\n", helpers);
    for (uint32_t i = 0; i < sockets->count; ++i) {
        const cb_socket *k = &sockets->items[i];
        const double *b = k->bind_transform;
        printf("  socket '%s' (node %d) on joint '%s' (bone %u), bind position (%.4g, %.4g, %.4g)\n", k->name, k->node,
               m->nodes[m->skins[skin].joints[k->bone]].name, k->bone, b[12], b[13], b[14]);
    }
}

/* A mesh node's primitives: primitives[first, end) (the loader keeps a node's together). */
typedef struct mesh_run {
    uint32_t first, end;
} mesh_run;

static mesh_run node_primitives(const cb_model *m, uint32_t first)
{
    mesh_run r = {first, first + 1};
    while (r.end < m->primitive_count && m->primitives[r.end].node == m->primitives[first].node) ++r.end;
    return r;
}

/* Whether two nodes draw the same mesh: the same primitives, vertex for vertex (what an
 * exporter writes for instances of one mesh). */
static bool same_mesh(const cb_model *m, mesh_run a, mesh_run b)
{
    if (a.end - a.first != b.end - b.first) return false;
    for (uint32_t i = 0; i < a.end - a.first; ++i) {
        const cb_primitive *x = &m->primitives[a.first + i], *y = &m->primitives[b.first + i];
        if (x->vertex_count != y->vertex_count || x->index_count != y->index_count || x->skin != y->skin ||
            !x->normals != !y->normals ||
            (x->vertex_count && memcmp(x->positions, y->positions, (size_t)x->vertex_count * 3 * sizeof(float))))
            return false;
    }
    return true;
}

/* One line per mesh node (its primitives summed), and one for a row of nodes drawing the same
 * mesh: "mesh nodes 'a' .. 'b' (12 nodes, one mesh): ..." rather than a line each. */
static void print_mesh_nodes(const cb_model *m)
{
    for (uint32_t p = 0; p < m->primitive_count;) {
        mesh_run first = node_primitives(m, p), last = first;
        uint32_t nodes = 1, vertices = 0, indices = 0;
        while (last.end < m->primitive_count && same_mesh(m, first, node_primitives(m, last.end)))
            last = node_primitives(m, last.end), ++nodes;
        for (uint32_t i = first.first; i < first.end; ++i) vertices += m->primitives[i].vertex_count, indices += m->primitives[i].index_count;
        const cb_primitive *pr = &m->primitives[first.first];
        char prims[32] = "";
        if (first.end - first.first > 1) snprintf(prims, sizeof prims, "%u primitives, ", first.end - first.first);
        if (nodes == 1) printf("  mesh node '%s' (node %d): ", m->nodes[pr->node].name, pr->node);
        else printf("  mesh nodes '%s' .. '%s' (nodes %d .. %d: %u nodes, one mesh): each ", m->nodes[pr->node].name,
                    m->nodes[m->primitives[last.first].node].name, pr->node, m->primitives[last.first].node, nodes);
        printf("%s%u vertices, %u indices, skin %d%s\n", prims, vertices, indices, pr->skin, pr->normals ? "" : ", no normals");
        p = last.end;
    }
}

static void print_text(const cb_model *m, int skin, const clip_facts *facts, double fps)
{
    printf("%s\n", m->source);
    printf("  %u nodes, %u skin%s, %u skinned primitive%s, %u clip%s\n", m->node_count, m->skin_count,
           m->skin_count == 1 ? "" : "s", m->primitive_count, m->primitive_count == 1 ? "" : "s", m->animation_count,
           m->animation_count == 1 ? "" : "s");
    for (uint32_t s = 0; s < m->skin_count; ++s) {
        const cb_skin *sk = &m->skins[s];
        printf("  skin %u '%s': %u joints, root joint '%s', %llu vertices%s\n", s, sk->name, sk->joint_count,
               m->nodes[sk->joints[cb_skin_root_joint(m, (int32_t)s)]].name,
               (unsigned long long)cb_model_skin_vertex_count(m, (int32_t)s), (int)s == skin ? " (baked)" : "");
    }
    print_mesh_nodes(m);
    if (m->ignored_morph_channels)
        printf("  warning: %u morph-weight channel%s ignored (palettes carry joints only)\n", m->ignored_morph_channels,
               m->ignored_morph_channels == 1 ? "" : "s");
    if (!m->animation_count) return;
    int w = 24; /* the clip column fits the longest name (exporters prefix them: "AnimalArmature|Walk") */
    for (uint32_t a = 0; a < m->animation_count; ++a)
        if ((int)strlen(m->animations[a].name) > w) w = (int)strlen(m->animations[a].name);
    printf("  %-*s %8s %9s %6s  %-18s %-8s %7s  %s\n", w, "clip", "start s", "length s", "keys", "interpolation", "loops",
           "frames", "root velocity (units/s)");
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        const cb_animation *anim = &m->animations[a];
        const clip_facts *f = &facts[a];
        char interp[64];
        interp_list(f->interp_mask, interp, sizeof interp);
        if (f->analyzed) {
            char why[512];
            cb_loop_reason_text(&f->info, why, sizeof why);
            printf("  %-*s %8.4f %9.4f %6llu  %-18s %-8s %7u  (%.4g, %.4g, %.4g) ground %.4g\n", w, anim->name, anim->t0,
                   anim->t1 - anim->t0, (unsigned long long)f->keys, interp, f->info.loops ? "loop" : "one-shot",
                   f->info.frames, f->info.root_velocity[0], f->info.root_velocity[1], f->info.root_velocity[2],
                   f->info.ground_speed);
            printf("  %-*s %s; ground speed %.4g from %s (root %.4g, planted feet %.4g)\n", w, "", why, f->speed.speed, f->speed.method, f->speed.root, f->speed.feet);
            printf("  %-*s %s: %s\n", w, "", f->sync.speed ? "follows the speed" : "own rate", f->sync.reason);
            if (f->root_motion[0]) printf("  %-*s root motion %s\n", w, "", f->root_motion);
            if (f->speed.stride.stride) print_slide(w, &f->speed.stride, &f->travel), print_contacts(w, &f->speed.stride);
            if (f->travel.slide_mean > 0) printf("  %-*s per-row travel %s\n", w, "", f->travel.why);
        } else
            printf("  %-*s %8.4f %9.4f %6llu  %-18s %-8s %7u  -\n", w, anim->name, anim->t0, anim->t1 - anim->t0,
                   (unsigned long long)f->keys, interp, "-", cb_clip_step_count(anim->t1 - anim->t0, fps) + 1);
    }
}

static void print_json(const cb_model *m, int skin, const clip_facts *facts, const socket_list *sockets, double fps,
                       const cb_bake_job *planted)
{
    cb_json j;
    cb_json_init(&j, stdout);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "file", m->source);
    cb_json_int(&j, "nodes", m->node_count);
    cb_json_int(&j, "baked_skin", skin);
    cb_json_number(&j, "fps", fps);
    cb_json_array(&j, "skins");
    for (uint32_t s = 0; s < m->skin_count; ++s) {
        const cb_skin *sk = &m->skins[s];
        cb_json_object(&j, NULL);
        cb_json_int(&j, "index", s);
        cb_json_string(&j, "name", sk->name);
        cb_json_int(&j, "joints", sk->joint_count);
        cb_json_string(&j, "root_joint", m->nodes[sk->joints[cb_skin_root_joint(m, (int32_t)s)]].name);
        cb_json_int(&j, "vertices", (long long)cb_model_skin_vertex_count(m, (int32_t)s));
        cb_json_inline_array(&j, "joint_names");
        for (uint32_t k = 0; k < sk->joint_count; ++k) cb_json_string(&j, NULL, m->nodes[sk->joints[k]].name);
        cb_json_end(&j);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_array(&j, "mesh_primitives");
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *pr = &m->primitives[p];
        cb_json_object(&j, NULL);
        cb_json_int(&j, "node", pr->node);
        cb_json_string(&j, "node_name", m->nodes[pr->node].name);
        cb_json_int(&j, "skin", pr->skin);
        cb_json_int(&j, "vertices", pr->vertex_count);
        cb_json_int(&j, "indices", pr->index_count);
        cb_json_bool(&j, "normals", pr->normals != NULL);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_int(&j, "ignored_morph_channels", m->ignored_morph_channels);
    cb_roster_json_sockets(&j, sockets->items, sockets->count);
    cb_json_array(&j, "clips");
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        const cb_animation *anim = &m->animations[a];
        const clip_facts *f = &facts[a];
        cb_json_object(&j, NULL);
        cb_json_int(&j, "index", a);
        cb_json_string(&j, "name", anim->name);
        cb_json_number(&j, "start", anim->t0);
        cb_json_number(&j, "end", anim->t1);
        cb_json_number(&j, "duration", anim->t1 - anim->t0);
        cb_json_int(&j, "channels", anim->channel_count);
        cb_json_int(&j, "keys", (long long)f->keys);
        cb_json_inline_array(&j, "interpolation");
        for (int i = 0; i < 3; ++i)
            if (f->interp_mask & (1u << i)) cb_json_string(&j, NULL, interp_names[i]);
        cb_json_end(&j);
        if (f->analyzed) {
            char why[512];
            cb_loop_reason_text(&f->info, why, sizeof why);
            cb_json_bool(&j, "loops", f->info.loops);
            cb_json_string(&j, "loop_reason", why);
            if (f->info.loops && f->info.loop_reason == CB_LOOP_CLOSED_CORRECTED) /* the closing key slightly off */
                cb_json_number(&j, "loop_correction_mm_per_m", f->info.loop_correction_mm_per_m);
            cb_json_number(&j, "period", f->info.duration);
            cb_json_int(&j, "frames", f->info.frames);
            cb_json_number(&j, "effective_fps", f->info.effective_fps);
            cb_json_inline_array(&j, "root_displacement");
            for (int k = 0; k < 3; ++k) cb_json_number(&j, NULL, f->info.root_displacement[k]);
            cb_json_end(&j);
            cb_json_inline_array(&j, "root_velocity");
            for (int k = 0; k < 3; ++k) cb_json_number(&j, NULL, f->info.root_velocity[k]);
            cb_json_end(&j);
            cb_json_number(&j, "ground_speed", f->speed.speed);
            cb_json_number(&j, "root_speed", f->speed.root);
            cb_json_number(&j, "feet_speed", f->speed.feet);
            cb_json_string(&j, "speed_method", f->speed.method);
            cb_json_string(&j, "sync", f->sync.speed ? "speed" : "time");
            cb_json_string(&j, "sync_reason", f->sync.reason);
            cb_json_string(&j, "root_motion", f->in_place ? "in-place" : "keep");
            if (f->root_motion[0]) cb_json_string(&j, "root_motion_reason", f->root_motion);
            cb_roster_json_stride(&j, &f->speed.stride);
            cb_roster_json_row_travel(&j, &f->travel);
        }
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_array(&j, "skipped_clips");
    for (uint32_t i = 0; i < m->skipped_clip_count; ++i) {
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", m->skipped_clips[i].name);
        cb_json_string(&j, "reason", m->skipped_clips[i].reason);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    if (planted) cli_plant_json(&j, planted);
    cb_warnings warnings = {0};
    cb_model_warnings(m, true, &warnings);
    cli_json_warnings(&j, &warnings);
    cb_warnings_free(&warnings);
    cb_json_end(&j);
}

/* --plant-feet: what a bake with it would change, from a job planned at the fixed --fps (no rate
 * search: planting does not depend on the rates). */
static cb_status plan_planted(cb_model *m, int skin, double fps, const cb_limits *limits, cb_bake_job *job, cb_error *err)
{
    job->model = m, job->skin = skin, job->limits = *limits;
    job->settings.plant_feet = true, job->settings.fps_auto = false, job->settings.fps = fps;
    return cb_bake_job_plan(job, err);
}

int cmd_info(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output out;
    if (cli_take_output(&argc, argv, &out)) return CLI_EXIT_USAGE;
    const char *path = NULL, *fps_text = "30", *skin_name = NULL;
    bool json = false, plant = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json}, {"--fps", "N", &fps_text, NULL},
                                  {"--skin", "NAME|INDEX", &skin_name, NULL}, {"--plant-feet", NULL, NULL, &plant}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &path, 1, 1, &help);
    if (help) return fputs(cmd_info_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    double fps;
    if (!cli_parse_double(fps_text, &fps) || !cb_fps_valid(fps))
        return cli_usage_error("info", "--fps wants a number between 0 and 1000");
    cb_error err = {0};
    cb_model *m = cli_load_model(&out, path, &limits, &err);
    if (!m) return cli_report(&err);
    /* info describes every skin; clips are analysed with the one a bake would use. */
    int skin = -1;
    if (m->skin_count) {
        cb_error pick_err = {0};
        skin = cli_pick_skin(m, skin_name, &pick_err);
        if (skin < 0 && skin_name) err = pick_err;
        if (skin < 0 && !skin_name) skin = 0;
    }
    clip_facts *facts = calloc(m->animation_count + 1, sizeof *facts);
    if (!facts) cb_fail(&err, CB_ERR_INTERNAL, "out of memory");
    socket_list sockets = {0};
    if (!err.status) gather_clips(m, skin, fps, &limits, facts, &sockets, &err);
    cb_bake_job job;
    cb_bake_job_init(&job);
    bool planted = plant && skin >= 0 && !err.status && !plan_planted(m, skin, fps, &limits, &job, &err);
    if (!err.status && json) print_json(m, skin, facts, &sockets, fps, planted ? &job : NULL);
    if (!err.status && !json) print_text(m, skin, facts, fps), print_sockets(m, skin, &sockets, sockets.helpers);
    if (!err.status && !json && planted) cli_plant_print(&job);
    if (!err.status && !json && !out.quiet) { /* what a bake would leave out (-q: not said) */
        cb_warnings warnings = {0};
        cb_model_warnings(m, true, &warnings);
        cli_print_warnings(&warnings, false);
        cb_warnings_free(&warnings);
    }
    cb_bake_job_free(&job);
    free(facts);
    free(sockets.items);
    cb_model_free(m);
    return err.status ? cli_report(&err) : 0;
}
