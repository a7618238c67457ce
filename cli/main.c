/* main.c - the crowdbake command: dispatches to a subcommand. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

static const cli_command commands[] = {
    {"info", "what a model holds: skins, joints, meshes, clips", cmd_info_usage, cmd_info},
    {"sample", "the joint matrices of each baked frame, as JSON", cmd_sample_usage, cmd_sample},
    {"bake", "bake a model's clips into a bone-matrix palette (.pal / .exr / .ktx2 / .bvat.json)", cmd_bake_usage, cmd_bake},
    {"inspect", "the header and clip table of a palette; decode a frame", cmd_inspect_usage, cmd_inspect},
    {"verify", "skin with a palette as the runtime does; compare with the glTF", cmd_verify_usage, cmd_verify},
    {"preview", "a contact sheet PNG of a palette skinning its model", cmd_preview_usage, cmd_preview},
    {"mesh", "the runtime-ready mesh: palette bones, fewer influences, quantized, batched", cmd_mesh_usage, cmd_mesh},
    {"vat", "bake a vertex animation texture of the same frames, to compare", cmd_vat_usage, cmd_vat},
    {"report", "palette vs VAT bytes and the roster's VRAM budget", cmd_report_usage, cmd_report},
    {"roster", "merge the manifest fragments of types baked one action each", cmd_roster_usage, cmd_roster},
    {"view", "watch a herd in the browser: palette and VAT side by side", cmd_view_usage, cmd_view},
};

static void print_help(FILE *out)
{
    fprintf(out,
            "crowdbake %s - bake skinned glTF animation into GPU bone-matrix palettes for crowds\n\n"
            "usage: crowdbake COMMAND [options]\n\ncommands:\n",
            CROWDBAKE_VERSION);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i)
        fprintf(out, "  %-9s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\n'crowdbake help COMMAND' (or 'crowdbake COMMAND --help') describes a command; 'crowdbake --version'\n"
                 "(-V) prints the version.\n"
                 "exit codes: 0 ok, 1 internal error, 2 usage, 3 over budget, 4 invalid input, 5 I/O error,\n"
                 "            6 verification failed\n");
}

static const cli_command *find_command(const char *name)
{
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i)
        if (strcmp(name, commands[i].name) == 0) return &commands[i];
    return NULL;
}

static int unknown_command(const char *name)
{
    const char *guess = cb_closest_name(name, &commands[0].name, sizeof commands / sizeof commands[0], sizeof commands[0]);
    if (guess) fprintf(stderr, "crowdbake: unknown command '%s'; did you mean '%s'? (see 'crowdbake --help')\n", name, guess);
    else fprintf(stderr, "crowdbake: unknown command '%s' (see 'crowdbake --help')\n", name);
    return CLI_EXIT_USAGE;
}

/* `crowdbake help [COMMAND]`, as git and cargo take it: the command's --help. */
static int help(int argc, char **argv)
{
    if (argc < 3) return print_help(stdout), 0;
    const cli_command *c = find_command(argv[2]);
    if (!c) return unknown_command(argv[2]);
    char *args[] = {argv[2], "--help", NULL};
    return c->run(2, args);
}

int main(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
        print_help(argc < 2 ? stderr : stdout);
        return argc < 2 ? CLI_EXIT_USAGE : 0;
    }
    if (strcmp(argv[1], "help") == 0) return help(argc, argv);
    if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "-V") == 0) {
        printf("crowdbake %s\n", CROWDBAKE_VERSION);
        return 0;
    }
    cli_remove_temporaries_on_signals(); /* an interrupted bake leaves no partial file */
    const cli_command *c = find_command(argv[1]);
    return c ? c->run(argc - 1, argv + 1) : unknown_command(argv[1]);
}
