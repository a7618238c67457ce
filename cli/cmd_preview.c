/* cmd_preview.c - `crowdbake preview MODEL PALETTE -o sheet.png`: a contact sheet of the bake. */
#include <stdio.h>
#include <string.h>

#include "crowdbake/pal_view.h"
#include "report/preview.h"
#include "cli.h"

const char cmd_preview_usage[] =
    "usage: crowdbake preview MODEL PALETTE.pal|.exr|.ktx2 -o SHEET.png [--columns N] [--cell PIXELS] [--skin NAME|INDEX] [-q] [-v]\n\n"
    "Renders a contact sheet: a row per clip (in the palette's order), N frames across (default 6),\n"
    "the model's mesh skinned from the palette by the shipped GLSL on Mesa's software OpenGL, flat\n"
    "shaded, framed by each clip's bounds. One look tells whether the bake is right.\n";

int cmd_preview(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    cli_output said;
    if (cli_take_output(&argc, argv, &said)) return CLI_EXIT_USAGE;
    const char *pos[2] = {0}, *out = NULL, *cols = NULL, *cell = NULL, *skin_name = NULL;
    bool help;
    const cli_option options[] = {{"-o", "FILE", &out, NULL}, {"--output", "FILE", &out, NULL}, {"--columns", "N", &cols, NULL},
                                  {"--cell", "PIXELS", &cell, NULL}, {"--skin", "NAME|INDEX", &skin_name, NULL}};
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
    const cb_palette *p = &b.view;
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
    cli_baked_close(&b);
    return err.status ? cli_report(&err) : 0;
}
