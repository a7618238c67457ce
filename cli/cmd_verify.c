/* cmd_verify.c - `crowdbake verify MODEL PALETTE`: skins the model with the palette exactly as
 * the shipped shaders do and compares with exact skinning from the glTF. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/json.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"
#include "cli.h"

const char cmd_verify_usage[] =
    "usage: crowdbake verify MODEL PALETTE.pal|.exr|.ktx2 [--max-error MM_PER_M] [--random N] [--skin NAME|INDEX] [--json]\n"
    "                        [--clip A,B | --exclude-clip A,B] [-q] [-v]\n\n"
    "Skins the model's mesh from the palette the way the runtime shaders do (two adjacent rows\n"
    "blended, up to 4 weighted bones, loops wrap, one-shots clamp) and compares it with exact float64\n"
    "skinning from the glTF: at every baked frame (the encoding's error), at every mid-frame and at N\n"
    "random times (default 64; the blending's error). Reports per clip the max and mean vertex error\n"
    "in model units and in mm per metre of model height, and the worst vertex and time. Exits 6 when\n"
    "an error exceeds --max-error (mm per metre of height). --clip verifies only the palette's clips\n"
    "named, --exclude-clip all but those. -q prints nothing but why it fails: the exit code says.\n";

int cmd_verify(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output out;
    if (cli_take_output(&argc, argv, &out)) return CLI_EXIT_USAGE;
    const char *pos[2] = {0}, *max_text = NULL, *random_text = NULL, *skin_name = NULL, *clips = NULL, *excluded = NULL;
    bool json = false, help;
    const cli_option options[] = {{"--max-error", "MM_PER_M", &max_text, NULL}, {"--random", "N", &random_text, NULL},
                                  {"--skin", "NAME|INDEX", &skin_name, NULL}, {"--json", NULL, NULL, &json},
                                  {"--clip", "A,B", &clips, NULL}, {"--exclude-clip", "A,B", &excluded, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], pos, 2, 2, &help);
    if (help) return fputs(cmd_verify_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    double max_error = -1;
    unsigned random_times = 64;
    if (max_text && (!cli_parse_double(max_text, &max_error) || max_error < 0)) return cli_usage_error("verify", "--max-error wants mm per metre");
    if (random_text && !cli_parse_u32(random_text, &random_times)) return cli_usage_error("verify", "--random wants a count");
    cb_error err = {0};
    cli_baked b;
    if (cli_open_baked(&out, "verify", pos[0], pos[1], &limits, skin_name, &b, &err)) return cli_report(&err);
    const cb_palette *pv = &b.view;
    const cb_model *m = b.model;
    bool *skip = calloc(pv->clip_count + 1, sizeof *skip);
    if (!skip) cb_fail(&err, CB_ERR_INTERNAL, "out of memory");
    cb_sampler *s = !skip || cli_palette_clip_options(pv, pos[1], clips, excluded, skip, &err) ? NULL : cb_sampler_create(m, b.skin, &err);
    if (!s) {
        free(skip);
        cli_baked_close(&b);
        return cli_report(&err);
    }
    double lo[3], hi[3], worst = 0, height = cb_skin_rest_bounds(s, lo, hi);
    cb_json j;
    if (json) {
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "model", pos[0]);
        cb_json_string(&j, "palette", pos[1]);
        cb_json_number(&j, "model_height", height);
        cb_json_array(&j, "clips");
    }
    int name_width = 20; /* the clip column fits the longest name */
    for (uint32_t c = 0; c < pv->clip_count; ++c)
        if ((int)strlen(pv->clips[c].name) > name_width) name_width = (int)strlen(pv->clips[c].name);
    bool table = !json && !out.quiet; /* -q: only the exit status (and why, over --max-error) */
    if (table) {
        printf("%s with %s (%s/%s, model height %.4g):\n  %-*s %12s %12s %12s %12s %12s %13s  %s\n", pos[1], pos[0],
               cb_layout_name(pv->layout), cb_precision_name(pv->precision), height, name_width, "clip", "rows max", "rows mean",
               "between max", "between mean", "rows mm/m", "between mm/m", "worst vertex @ time");
    }
    for (uint32_t c = 0; c < pv->clip_count && !err.status; ++c) {
        if (skip[c]) continue;
        int32_t a = cb_model_find_animation(m, pv->clips[c].name);
        if (a < 0) {
            cb_fail(&err, CB_ERR_INPUT, "%s: has no clip '%s' that %s holds; verify the model the palette was baked from",
                    pos[0], pv->clips[c].name, pos[1]);
            break;
        }
        cb_clip_error e;
        double t0 = cli_seconds();
        if (cb_verify_clip(s, pv, b.texels, c, a, random_times, &e, &err)) break;
        cli_verbose(&out, "clip '%s': %u rows, their %u mid-points and %u random times compared in %.3f s", pv->clips[c].name,
                    pv->clips[c].frames, pv->clips[c].frames, random_times, cli_seconds() - t0);
        worst = e.quant_max > worst ? e.quant_max : worst;
        worst = e.interp_max > worst ? e.interp_max : worst;
        if (json) {
            cb_json_object(&j, NULL);
            cb_json_string(&j, "name", pv->clips[c].name);
            cb_json_number(&j, "rows_max", e.quant_max);
            cb_json_number(&j, "rows_mean", e.quant_mean);
            cb_json_number(&j, "between_max", e.interp_max);
            cb_json_number(&j, "between_mean", e.interp_mean);
            cb_json_number(&j, "rows_max_mm_per_m", cb_mm_per_m(e.quant_max, height));
            cb_json_number(&j, "between_max_mm_per_m", cb_mm_per_m(e.interp_max, height));
            cb_json_int(&j, "worst_vertex", (long long)e.worst_vertex);
            cb_json_number(&j, "worst_time", e.worst_time);
            cb_json_end(&j);
        } else if (table) {
            printf("  %-*s %12.4g %12.4g %12.4g %12.4g %12.3f %13.3f  %llu @ %.3f s\n", name_width, pv->clips[c].name, e.quant_max,
                   e.quant_mean, e.interp_max, e.interp_mean, cb_mm_per_m(e.quant_max, height), cb_mm_per_m(e.interp_max, height),
                   (unsigned long long)e.worst_vertex, e.worst_time);
        }
    }
    if (!err.status) {
        if (json) {
            cb_json_end(&j);
            cb_json_number(&j, "max_error", worst);
            cb_json_number(&j, "max_error_mm_per_m", cb_mm_per_m(worst, height));
            cb_json_end(&j);
        } else if (table) {
            printf("  worst %.4g units = %.3f mm per m of height%s\n", worst, cb_mm_per_m(worst, height),
                   max_error >= 0 ? (cb_mm_per_m(worst, height) > max_error ? " — over --max-error" : " — within --max-error") : "");
        }
    }
    cb_sampler_free(s);
    free(skip);
    cli_baked_close(&b);
    if (err.status) return cli_report(&err);
    if (max_error >= 0 && cb_mm_per_m(worst, height) > max_error) {
        fprintf(stderr, "crowdbake: %s: worst error %.3f mm/m is over --max-error %g\n", pos[1], cb_mm_per_m(worst, height), max_error);
        return CLI_EXIT_VERIFY;
    }
    return 0;
}
