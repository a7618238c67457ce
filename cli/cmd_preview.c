/* cmd_preview.c - `crowdbake preview MODEL PALETTE -o sheet.png`: a contact sheet of the bake. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/pal_view.h"
#include "report/preview.h"
#include "cli.h"

const char cmd_preview_usage[] =
    "usage: crowdbake preview MODEL PALETTE.pal|.exr|.ktx2 -o SHEET.png [--columns N] [--cell PIXELS] [--skin NAME|INDEX]\n"
    "                         [--clip A,B | --exclude-clip A,B] [-q] [-v]\n\n"
    "Renders a contact sheet: a row per clip (in the palette's order), N frames across (default 6),\n"
    "the model's mesh skinned from the palette by the shipped GLSL on Mesa's software OpenGL, flat\n"
    "shaded, framed by each clip's bounds. One look tells whether the bake is right. --clip draws\n"
    "only the palette's clips named (found as verify's --clip finds them), --exclude-clip all but those.\n";

/* The palette's clips the options leave in, as a view over the same texels (*kept: the clip
 * table to free). */
static cb_status chosen_clips(const cb_palette *p, const char *palette, const char *clips, const char *excluded,
                              cb_palette *view, cb_palette_clip **kept, cb_error *err)
{
    *view = *p, *kept = NULL;
    if (!clips && !excluded) return CB_OK;
    bool *skip = calloc(p->clip_count + 1, sizeof *skip);
    *kept = calloc(p->clip_count + 1, sizeof **kept);
    if (!skip || !*kept) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    else if (!cli_palette_clip_options(p, palette, clips, excluded, skip, err)) {
        view->clips = *kept, view->clip_count = 0;
        for (uint32_t c = 0; c < p->clip_count; ++c)
            if (!skip[c]) (*kept)[view->clip_count++] = p->clips[c];
        if (!view->clip_count) cb_fail(err, CB_ERR_SETTINGS, "%s: no clip left to draw after --exclude-clip", palette);
    }
    free(skip);
    return err->status;
}

int cmd_preview(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output said;
    if (cli_take_output(&argc, argv, &said)) return CLI_EXIT_USAGE;
    const char *pos[2] = {0}, *out = NULL, *cols = NULL, *cell = NULL, *skin_name = NULL, *clips = NULL, *excluded = NULL;
    bool help;
    const cli_option options[] = {{"-o", "FILE", &out, NULL}, {"--output", "FILE", &out, NULL}, {"--columns", "N", &cols, NULL},
                                  {"--cell", "PIXELS", &cell, NULL}, {"--skin", "NAME|INDEX", &skin_name, NULL},
                                  {"--clip", "A,B", &clips, NULL},  {"--exclude-clip", "A,B", &excluded, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], pos, 2, 2, &help);
    if (help) return fputs(cmd_preview_usage, stdout), fputs(cli_output_usage, stdout), 0;
    if (rc) return rc;
    if (!out) return cli_usage_error("preview", "-o SHEET.png is required");
    cb_preview_options opt = {6, 160, NULL};
    if (cols && (!cli_parse_u32(cols, &opt.columns) || !opt.columns)) return cli_usage_error("preview", "--columns wants a count");
    if (cell && (!cli_parse_u32(cell, &opt.cell) || opt.cell < 16)) return cli_usage_error("preview", "--cell wants 16 pixels or more");
    cb_error err = {0};
    cli_baked b;
    if (cli_open_baked(&said, "preview", pos[0], pos[1], &limits, skin_name, &b, &err)) return cli_report(&err);
    cb_palette chosen;
    cb_palette_clip *kept = NULL;
    if (chosen_clips(&b.view, pos[1], clips, excluded, &chosen, &kept, &err)) {
        free(kept);
        cli_baked_close(&b);
        return cli_report(&err);
    }
    const cb_palette *p = &chosen;
    char title[512];
    const char *model_name = strrchr(pos[0], '/') ? strrchr(pos[0], '/') + 1 : pos[0];
    const char *palette_name = strrchr(pos[1], '/') ? strrchr(pos[1], '/') + 1 : pos[1];
    snprintf(title, sizeof title, "%s with %s", model_name, palette_name);
    opt.title = title;
    double t0 = cli_seconds();
    if (!cb_preview_write(p, b.texels, b.model, b.skin, &opt, out, &err)) cli_verbose(&said, "drew and wrote %s in %.3f s", out, cli_seconds() - t0);
    if (!err.status && !said.quiet) {
        printf("%s: %u clip%s x %u frame%s (%ux%u pixels):", out, p->clip_count, p->clip_count == 1 ? "" : "s", opt.columns,
               opt.columns == 1 ? "" : "s", opt.columns * opt.cell,
               CB_PREVIEW_HEADER + p->clip_count * (CB_PREVIEW_BAND + opt.cell));
        for (uint32_t c = 0; c < p->clip_count; ++c) printf(" %s%s", c ? "/ " : "", p->clips[c].name);
        printf(" (rows, top to bottom)\n");
    }
    free(kept);
    cli_baked_close(&b);
    return err.status ? cli_report(&err) : 0;
}
