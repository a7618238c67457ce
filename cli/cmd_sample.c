/* cmd_sample.c - `crowdbake sample MODEL --fps N --json`: the joint matrices per clip and
 * frame, exactly as they will be baked. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/json.h"
#include "crowdbake/bake.h"
#include "cli.h"

const char cmd_sample_usage[] =
    "usage: crowdbake sample MODEL --fps N --json [--clip NAME] [--frame I] [--skin NAME|INDEX]\n"
    "                        [--root-motion keep|in-place|loops-in-place] [-q] [-v]\n\n"
    "Prints the joint matrices (4x4, column-major, glTF order) of every baked frame of every clip,\n"
    "or of one clip / one frame: the debugging view of what 'crowdbake bake' stores.\n";

static void write_clip(cb_json *j, cb_sampler *s, const cb_model *m, const cb_clip_info *clip, long frame,
                       cb_root_motion rm, double *mats)
{
    uint32_t joints = m->skins[cb_sampler_skin(s)].joint_count;
    cb_json_object(j, NULL);
    cb_json_string(j, "name", m->animations[clip->animation].name);
    cb_json_bool(j, "loops", clip->loops);
    cb_json_int(j, "frames", clip->frames);
    cb_json_number(j, "effective_fps", clip->effective_fps);
    cb_json_array(j, "samples");
    for (uint32_t f = 0; f < clip->frames; ++f) {
        if (frame >= 0 && (uint32_t)frame != f) continue;
        cb_clip_frame_matrices(s, clip, f, rm, mats);
        cb_json_object(j, NULL);
        cb_json_int(j, "frame", f);
        cb_json_number(j, "t", cb_clip_frame_time(clip, f));
        cb_json_array(j, "joints");
        for (uint32_t k = 0; k < joints; ++k) {
            cb_json_inline_array(j, NULL);
            for (int e = 0; e < 16; ++e) cb_json_number(j, NULL, mats[(size_t)k * 16 + e]);
            cb_json_end(j);
        }
        cb_json_end(j);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_end(j);
}

int cmd_sample(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output out;
    if (cli_take_output(&argc, argv, &out)) return CLI_EXIT_USAGE;
    const char *path = NULL, *fps_text = NULL, *clip_name = NULL, *frame_text = NULL, *skin_name = NULL, *rm_text = "keep";
    bool json = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json},          {"--fps", "N", &fps_text, NULL},
                                  {"--clip", "NAME", &clip_name, NULL},   {"--frame", "I", &frame_text, NULL},
                                  {"--skin", "NAME|INDEX", &skin_name, NULL}, {"--root-motion", "keep|in-place|loops-in-place", &rm_text, NULL}};
    int rc = cli_parse(argc, argv, options, 6, &path, 1, 1, &help);
    if (help) return fputs(cmd_sample_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    double fps;
    unsigned frame = 0;
    if (!fps_text) return cli_usage_error("sample", "--fps is required");
    if (!cli_parse_double(fps_text, &fps) || !cb_fps_valid(fps))
        return cli_usage_error("sample", "--fps wants a number between 0 and 1000");
    if (frame_text && !cli_parse_u32(frame_text, &frame)) return cli_usage_error("sample", "--frame wants a frame index");
    if (!json) return cli_usage_error("sample", "only --json output exists; add --json");
    cb_root_motion rm;
    if (!cb_root_motion_parse(rm_text, &rm)) return cli_usage_error("sample", "--root-motion is keep, in-place or loops-in-place");

    cb_error err = {0};
    cb_model *m = cli_load_model(&out, path, &limits, &err);
    if (!m) return cli_report(&err);
    int skin = cli_pick_skin(m, skin_name, &err);
    int clip_index = -1;
    char why[512] = "the model has no clip";
    if (!err.status && clip_name &&
        (clip_index = m->animation_count ? cli_match_clip(clip_name, &m->animations[0].name, m->animation_count,
                                                          sizeof m->animations[0], why, sizeof why) : -1) < 0)
        cb_fail(&err, CB_ERR_SETTINGS, "%s: --clip %s: %s (see 'crowdbake info')", path, clip_name, why);
    cb_sampler *s = err.status ? NULL : cb_sampler_create(m, skin, &err);
    double *mats = s ? malloc((size_t)m->skins[skin].joint_count * 16 * sizeof(double)) : NULL;
    if (s && !mats) cb_fail(&err, CB_ERR_INTERNAL, "out of memory");
    if (!err.status) {
        cb_json j;
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "file", path);
        cb_json_string(&j, "skin", m->skins[skin].name);
        cb_json_number(&j, "fps", fps);
        cb_json_string(&j, "root_motion", rm_text);
        cb_json_array(&j, "clips");
        for (uint32_t a = 0; a < m->animation_count && !err.status; ++a) {
            if (clip_index >= 0 && (uint32_t)clip_index != a) continue;
            cb_clip_info clip;
            if (cb_clip_analyze(s, (int32_t)a, fps, -1, &limits, &clip, &err)) break;
            if (frame_text && frame >= clip.frames) {
                cb_fail(&err, CB_ERR_SETTINGS, "clip '%s' has %u frames at %g fps; --frame %u is past its end",
                        m->animations[a].name, clip.frames, fps, frame);
                break;
            }
            cli_verbose(&out, "clip '%s': %u frames at %.4g fps (%s)", m->animations[a].name, clip.frames, clip.effective_fps,
                        clip.loops ? "loops: its last pose is its first" : "one-shot");
            write_clip(&j, s, m, &clip, frame_text ? (long)frame : -1, rm, mats);
        }
        cb_json_end(&j);
        cb_json_end(&j);
    }
    free(mats);
    cb_sampler_free(s);
    cb_model_free(m);
    return err.status ? cli_report(&err) : 0;
}
