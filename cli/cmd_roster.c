/* cmd_roster.c - `crowdbake roster merge FRAGMENTS... -o roster.json`: the manifest of a roster
 * whose types were baked one action each (`crowdbake bake CATALOG --type NAME`). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "roster/roster.h"
#include "cli.h"

const char cmd_roster_usage[] =
    "usage: crowdbake roster merge FRAGMENT... -o roster.json [-q]\n\n"
    "Writes a roster's manifest from the fragments 'crowdbake bake CATALOG.toml --type NAME' wrote,\n"
    "one per animal type of the catalog (each type baked as its own build action, docs/bazel.md).\n"
    "The manifest is byte-identical to the one 'crowdbake bake CATALOG.toml' writes: types whose\n"
    "rig, bind pose, clips and settings are equal share the palette of the first by name, as there\n"
    "(each type's action baked its own copy; the manifest names the first's). The catalog is the\n"
    "one the fragments name; nothing else is read. A missing, repeated or damaged fragment is an\n"
    "error naming it; a type that failed is listed under \"failed\" and the merge exits non-zero.\n"
    "  -o, --output FILE   the manifest (written only when its bytes change)\n"
    "  -q, --quiet         no summary line\n";

static int merge(int argc, char **argv)
{
    const char *output = NULL;
    bool quiet = false;
    char **fragments = calloc((size_t)argc + 1, sizeof *fragments);
    uint32_t count = 0;
    if (!fragments) return CLI_EXIT_INTERNAL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
            free(fragments);
            return fputs(cmd_roster_usage, stdout), 0;
        } else if (strcmp(argv[i], "-o") == 0 || strcmp(argv[i], "--output") == 0) {
            if (i + 1 == argc) return free(fragments), cli_usage_error("roster", "%s needs a FILE (the manifest)", argv[i]);
            output = argv[++i];
        } else if (strcmp(argv[i], "-q") == 0 || strcmp(argv[i], "--quiet") == 0) {
            quiet = true;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            free(fragments);
            return cli_usage_error("roster", "unknown option '%s' for roster merge", argv[i]);
        } else {
            fragments[count++] = argv[i];
        }
    }
    if (!output) return free(fragments), cli_usage_error("roster", "-o roster.json is required");
    if (!count) return free(fragments), cli_usage_error("roster", "roster merge needs the fragments of every type");
    cb_error err = {0};
    cb_catalog cat;
    cb_roster r;
    cb_status rc = cb_roster_merge(fragments, count, output, &cat, &r, &err);
    if (!quiet && r.types)
        printf("crowdbake: %u types (%u sharing a palette, %u failed) from %u fragments; manifest %s%s\n", r.type_count,
               r.shared, r.failed, count, output, r.manifest_written ? "" : " (unchanged)");
    if (rc && r.failed > 1) fprintf(stderr, "crowdbake: %u animal types failed\n", r.failed);
    cb_roster_free(&r);
    if (cat.arena) cb_catalog_free(&cat);
    free(fragments);
    return rc ? cli_report(&err) : 0;
}

int cmd_roster(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
        fputs(cmd_roster_usage, argc < 2 ? stderr : stdout);
        return argc < 2 ? CLI_EXIT_USAGE : 0;
    }
    if (strcmp(argv[1], "merge") == 0) return merge(argc - 1, argv + 1);
    return cli_usage_error("roster", "unknown roster command '%s'; the one there is: merge", argv[1]);
}
