/* cmd_bake.c - placeholder until the palette writer lands. */
#include <stdio.h>
#include "cli.h"
const char cmd_bake_usage[] = "usage: crowdbake bake MODEL -o OUT.pal|OUT.exr\n";
int cmd_bake(int argc, char **argv) { (void)argc; (void)argv; fputs("crowdbake bake: not built yet\n", stderr); return 1; }
const char cmd_inspect_usage[] = "usage: crowdbake inspect FILE\n";
int cmd_inspect(int argc, char **argv) { (void)argc; (void)argv; return 1; }
