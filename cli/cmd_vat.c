/* cmd_vat.c - `crowdbake vat MODEL -o OUT.exr`: a real vertex animation texture of the same
 * frames a palette bakes, to compare both methods side by side. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake_pal.h"
#include "crowdbake/bake.h"
#include "crowdbake/exr.h"
#include "internal/json.h"
#include "cli.h"
#include "internal/plumbing.h"

const char cmd_vat_usage[] =
    "usage: crowdbake vat MODEL -o OUT.exr [--fps N] [--max-texture-size N] [--root-motion keep|in-place|loops-in-place]\n"
    "                     [--skin NAME|INDEX] [--exr-compression none|rle|zips|zip|piz] [--json]\n"
    "                     [--clip A,B | --exclude-clip A,B | --like PALETTE.pal] [-q] [-v]\n\n"
    "Bakes a vertex animation texture: every skinned vertex of every frame (framed like the palette's\n"
    "rows), positions and normals as RGBA16F layers position.* and normal.* of one EXR, a frame per\n"
    "texture row (a frame of more vertices than the limit takes several rows; rows wrap into column\n"
    "blocks). Prints its size and the error half-float positions cause, next to the size of the\n"
    "default palette of the same frames. --clip and --exclude-clip select clips as for 'bake'; a clip\n"
    "that cannot be sampled is skipped with a warning unless --clip names it. --like PALETTE.pal: the\n"
    "palette's clips at its clips' own rates (a default bake chooses a rate per clip), so the VAT's\n"
    "frames are the palette's rows one for one; a timed clip (.pal version 7) at its map's cell rate,\n"
    "one frame a cell, since a VAT has no map.\n";

/* --like PALETTE: the palette's clips, each at its own rate and loop, so the VAT's frames are
 * the palette's rows one for one (an error-bounded bake chooses a rate per clip). */
static cb_status plan_like(const cb_model *m, const char *palette, cb_clip_plan **plan, uint32_t *count, cb_error *err)
{
    cbpal_file f;
    char msg[256];
    if (cbpal_open(palette, 0, &f, msg, sizeof msg)) return cb_fail(err, CB_ERR_INPUT, "%s", msg);
    *plan = calloc(f.header.clip_count ? f.header.clip_count : 1, sizeof **plan);
    if (!*plan) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; *plan && i < f.header.clip_count && !err->status; ++i) {
        cbpal_clip c;
        cbpal_get_clip(&f, i, &c);
        int32_t a = cb_model_find_animation(m, c.name);
        if (a < 0)
            cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' is not a clip of %s; --like wants a palette baked from this model",
                    palette, c.name, m->source);
        else /* a timed clip at its cells' rate: what a VAT, which has no map, needs to play it as the palette does */
            (*plan)[i] = (cb_clip_plan){a, m->animations[a].name, (c.flags & CBPAL_CLIP_LOOPS) ? 1 : 0,
                                        (c.flags & CBPAL_CLIP_TIMED) ? c.cell_rate : c.fps, false, false, 0, NULL};
        *count = i + 1;
    }
    cbpal_close(&f);
    return err->status;
}

int cmd_vat(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output said;
    if (cli_take_output(&argc, argv, &said)) return CLI_EXIT_USAGE;
    const char *path = NULL, *out = NULL, *fps = NULL, *max = NULL, *rm = NULL, *skin_name = NULL, *comp = NULL,
               *clips = NULL, *excluded = NULL, *like = NULL;
    bool json = false, help;
    const cli_option options[] = {{"-o", "FILE", &out, NULL},          {"--output", "FILE", &out, NULL},
                                  {"--fps", "N", &fps, NULL},          {"--max-texture-size", "N", &max, NULL},
                                  {"--root-motion", "MODE", &rm, NULL}, {"--skin", "NAME|INDEX", &skin_name, NULL},
                                  {"--exr-compression", "NAME", &comp, NULL}, {"--json", NULL, NULL, &json},
                                  {"--clip", "A,B", &clips, NULL},     {"--exclude-clip", "A,B", &excluded, NULL},
                                  {"--like", "PALETTE.pal", &like, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &path, 1, 1, &help);
    if (help) return fputs(cmd_vat_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    if (!out) return cli_usage_error("vat", "-o OUT.exr is required");
    if (like && (fps || clips || excluded))
        return cli_usage_error("vat", "--like takes the palette's clips and rates: not with --fps, --clip or --exclude-clip");
    cb_bake_options o = cb_default_bake_options();
    o.limits = limits;
    unsigned max_size = o.max_texture_size;
    int compression = 0;
    if (fps && (!cli_parse_double(fps, &o.fps) || !cb_fps_valid(o.fps))) return cli_usage_error("vat", "--fps wants 0..1000");
    if (max && (!cli_parse_u32(max, &max_size) || max_size < 1)) return cli_usage_error("vat", "--max-texture-size wants a positive integer");
    o.max_texture_size = max_size;
    if (rm && !cb_root_motion_parse(rm, &o.root_motion)) return cli_usage_error("vat", "--root-motion is keep, in-place or loops-in-place");
    if (comp && !cb_exr_compression_parse(comp, &compression)) return cli_usage_error("vat", "--exr-compression: lossless only");
    cb_error err = {0};
    cb_model *m = cli_load_model(&said, path, &limits, &err);
    if (!m) return cli_report(&err);
    int skin = cli_pick_skin(m, skin_name, &err);
    cb_sampler *s = skin >= 0 ? cb_sampler_create(m, skin, &err) : NULL;
    cb_vat vat = {0};
    cb_clip_plan *plan = NULL;
    uint32_t planned = 0;
    if (s && !(like ? plan_like(m, like, &plan, &planned, &err) : cli_select_clips(m, clips, excluded, &plan, &planned, &err)) &&
        !cb_vat_bake(s, &o, plan, planned, true, &vat, &err)) {
        double t0 = cli_seconds();
        if (!cb_exr_write_vat(out, &vat, compression, &err)) cli_verbose(&said, "wrote %s in %.3f s", out, cli_seconds() - t0);
    }
    free(plan);
    cb_warnings warnings = {0};
    if (!err.status) cb_model_warnings(m, clips == NULL, &warnings);
    if (!err.status) {
        uint64_t bytes = (uint64_t)vat.geometry.width * vat.geometry.height * 16;
        cb_texture_geometry g;
        uint64_t pal = cb_palette_texture_bytes(m->skins[skin].joint_count, vat.frames, CB_LAYOUT_QPOS, CB_PRECISION_U16,
                                                o.max_texture_size, &g);
        double per_m = cb_mm_per_m(vat.max_error, vat.model_height);
        if (json) {
            cb_json j;
            cb_json_init(&j, stdout);
            cb_json_object(&j, NULL);
            cb_json_string(&j, "path", out);
            cb_json_int(&j, "vertices", (long long)vat.vertices);
            cb_json_int(&j, "rows", vat.frames);
            cb_json_int(&j, "width", vat.geometry.width);
            cb_json_int(&j, "height", vat.geometry.height);
            cb_json_int(&j, "blocks", vat.geometry.blocks);
            cb_json_int(&j, "texture_bytes", (long long)bytes);
            cb_json_number(&j, "max_error", vat.max_error);
            cb_json_number(&j, "max_error_mm_per_m", per_m);
            cb_json_int(&j, "palette_qpos_u16_bytes", (long long)pal);
            cli_json_warnings(&j, &warnings);
            cb_json_end(&j);
        } else if (said.quiet) {
            cli_print_warnings(&warnings, false); /* warnings still; no summary, no notes */
        } else {
            printf("%s: %llu vertices x %u frames, %ux%u texels (%u block%s), %.1f KiB of RGBA16F positions + normals, "
                   "max error %.3g units (%.3g mm per m); the qpos/u16 palette of the same frames: %.1f KiB (%.1fx smaller)\n",
                   out, (unsigned long long)vat.vertices, vat.frames, vat.geometry.width, vat.geometry.height,
                   vat.geometry.blocks, vat.geometry.blocks == 1 ? "" : "s", bytes / 1024.0, vat.max_error, per_m,
                   pal / 1024.0, pal ? (double)bytes / pal : 0);
            cli_print_warnings(&warnings, true);
        }
    }
    cb_warnings_free(&warnings);
    cb_vat_free(&vat);
    cb_sampler_free(s);
    cb_model_free(m);
    return err.status ? cli_report(&err) : 0;
}
