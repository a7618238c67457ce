/* cli.h - shared pieces of the crowdbake command: option parsing, loading, messages. */
#ifndef CB_CLI_H
#define CB_CLI_H

#include <stdbool.h>
#include <stddef.h>

#include "crowdbake/exr.h"
#include "crowdbake/gltf.h"
#include "crowdbake/ktx2.h"
#include "internal/json.h"
#include "crowdbake_pal.h" /* the runtime reader (installed as crowdbake_pal.h) */
#include "crowdbake/pal_view.h"
#include "catalog/catalog.h"

/* The command's exit codes (README "Exit codes"), apart from the library's cb_status. */
enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_INTERNAL = 1, /* a bug, or out of memory */
    CLI_EXIT_USAGE = 2,    /* bad command line (or a setting out of range) */
    CLI_EXIT_BUDGET = 3,   /* the roster exceeds its VRAM budget (report) */
    CLI_EXIT_INPUT = 4,    /* an input file is invalid or unsupported */
    CLI_EXIT_IO = 5,       /* a file could not be read or written */
    CLI_EXIT_VERIFY = 6    /* verification failed */
};
/* The exit code of a library status. */
int cli_exit_code(cb_status status);

typedef struct cli_option {
    const char *name;     /* "--fps" */
    const char *metavar;  /* NULL for a flag */
    const char **value;   /* where a value option stores its argument */
    bool *flag;           /* where a flag stores true */
} cli_option;

typedef struct cli_command {
    const char *name;
    const char *summary;
    const char *usage; /* full --help text */
    int (*run)(int argc, char **argv);
} cli_command;

/* Parses argv[1..] (argv[0] is the command name). Positionals fill `positional` in order.
 * Returns 0, or CLI_EXIT_USAGE after printing why; sets *help for -h/--help. */
int cli_parse(int argc, char **argv, const cli_option *options, size_t option_count, const char **positional,
              size_t min_positional, size_t max_positional, bool *help);

/* The flag that changes a setting an error names (cb_error.setting), or NULL. */
const char *cli_setting_flag(cb_setting setting);
/* An error's message with the flag that would fix it: "MESSAGE [--flag]". */
const char *cli_error_text(const cb_error *err, char *buf, size_t size);
/* Prints "crowdbake: MESSAGE [--flag]" to stderr and returns the error's exit code. */
int cli_report(const cb_error *err);
int cli_usage_error(const char *command, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

bool cli_parse_double(const char *text, double *out);
bool cli_parse_u32(const char *text, unsigned *out);

/* Takes the resource-limit options (--max-joints N, --max-frames N, --max-accessor-count N,
 * --max-file-size SIZE, --max-palette-size SIZE; SIZE like 512M or 2G) out of argv, whichever
 * command they come with. Returns 0 or CLI_EXIT_USAGE after printing why. */
int cli_take_limits(int *argc, char **argv, cb_limits *limits);
extern const char cli_limits_usage[];

/* -q/--quiet (nothing on stderr but errors) and -v/--verbose (each file read and written,
 * timings, decisions), which every command takes: cli_take_output removes them from argv, as
 * cli_take_limits does its options (up to a "--"), before the command's own parsing. With both,
 * -q wins. Progress lines go to stderr on a terminal or with -v, never with -q. */
typedef struct cli_output {
    bool quiet, verbose;
} cli_output;
int cli_take_output(int *argc, char **argv, cli_output *out);
extern const char cli_output_usage[];
/* "crowdbake: MESSAGE" on stderr with -v (and not -q). */
void cli_verbose(const cli_output *out, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
bool cli_progress(const cli_output *out);
double cli_seconds(void); /* monotonic, for -v's timings */
/* The running crowdbake executable's absolute path into path; "" where the system does not say. */
void cli_executable(char *path, size_t size);

/* Loads a model within `limits`; with -v, says what it read and how long it took (out may be NULL). */
cb_model *cli_load_model(const cli_output *out, const char *path, const cb_limits *limits, cb_error *err);
/* The skin a command works on: --skin NAME|INDEX, or the only one; an error otherwise. */
int cli_pick_skin(const cb_model *model, const char *skin_option, cb_error *err);
/* What a file holds, from its first bytes (not its name). */
typedef enum cli_file_kind { CLI_FILE_UNKNOWN, CLI_FILE_MODEL, CLI_FILE_PAL, CLI_FILE_EXR, CLI_FILE_MISSING, CLI_FILE_KTX2 } cli_file_kind;
cli_file_kind cli_file_kind_of(const char *path);

/* A palette (.pal, .exr or .ktx2) and the model it was baked from, as `verify` and `preview` take them. */
typedef struct cli_baked {
    cb_model *model;
    int skin;
    cb_palette view;        /* header and clip table; for a .pal, its texels stay in the mapping */
    const void *texels;     /* the payload the decoders read */
    cbpal_file pal;         /* a .pal: mapped, checksum verified */
    cb_exr_palette exr;     /* an .exr: decoded */
    cb_ktx2_palette ktx2;   /* a .ktx2: read */
    bool is_exr, is_ktx2, pal_open;
} cli_baked;

/* Opens MODEL PALETTE: checks each is the kind of file it should be (naming the order when
 * they are swapped), loads and picks the skin, compares bone counts. 0, or the error's status
 * with *err set and nothing left open; else close with cli_baked_close. */
cb_status cli_open_baked(const cli_output *out, const char *command, const char *model_path, const char *palette_path,
                         const cb_limits *limits, const char *skin_option, cli_baked *b, cb_error *err);
void cli_baked_close(cli_baked *b);

/* --clip A,B (only these, in this order; a clip skipped at load is then an error with its
 * reason) and --exclude-clip A,B (every clip but these). *plan is NULL (every clip) when
 * neither is given; else malloc'ed, *count entries. Names that are not clips are errors. */
cb_status cli_select_clips(const cb_model *model, const char *clips, const char *excluded, cb_clip_plan **plan,
                           uint32_t *count, cb_error *err);
/* --loop A,B and --one-shot A,B: these clips loop, or play once, whatever their poses say (the
 * bake decides from them otherwise: a clip whose last pose equals its first loops). Sets the
 * plan's loop for each; a plan of every clip in file order is made when *plan is NULL. A name
 * that is not a clip, not among the plan's, or given to both is an error. */
cb_status cli_override_loops(const cb_model *model, const char *loops, const char *one_shots, cb_clip_plan **plan,
                             uint32_t *count, cb_error *err);
/* Calls fn for each name of a comma-separated list (as --clip takes); stops at, and returns,
 * the first failure. */
cb_status cli_for_each_name(const char *list, cb_status (*fn)(const char *name, void *ctx), void *ctx);
/* The one clip-name matcher of every command that takes clip names: the name exactly, else
 * regardless of case, else the one clip whose name holds it (`--clip walk` for "Armature|Walk").
 * names[i] lies `stride` bytes after names[i-1] (as cb_closest_name reads them). The index, or
 * -1 with `why` saying so: "no clip 'X'; did you mean 'Y'?", or the clips an ambiguous name fits. */
int cli_match_clip(const char *typed, const char *const *names, size_t count, size_t stride, char *why, size_t size);
/* --clip and --exclude-clip naming a palette's clips (cli_match_clip), as verify and preview
 * take them; both at once is an error. skip[c] (clip_count entries, zeroed): the palette's clip
 * c is left out. */
cb_status cli_palette_clip_options(const cb_palette *p, const char *palette, const char *clips, const char *excluded,
                                   bool *skip, cb_error *err);
/* Whether a comma-separated list (as --clip takes) holds the name. */
bool cli_list_has(const char *list, const char *name);
/* "crowdbake: warning: ..." on stderr, one line each (notes too unless !notes, for -q); or a
 * "warnings" array of {kind, message}. */
void cli_print_warnings(const cb_warnings *warnings, bool notes);
void cli_json_warnings(cb_json *json, const cb_warnings *warnings);
/* plant_report.c: what --plant-feet changed per clip, as log lines and as --json's "plant_feet"
 * (nothing without it). */
void cli_plant_print(const cb_bake_job *job);
void cli_plant_json(cb_json *j, const cb_bake_job *job);

int cmd_info(int argc, char **argv);
int cmd_sample(int argc, char **argv);
int cmd_bake(int argc, char **argv);
int cmd_inspect(int argc, char **argv);
int cmd_vat(int argc, char **argv);
extern const char cmd_view_usage[];
int cmd_view(int argc, char **argv);
int cmd_verify(int argc, char **argv);
int cmd_preview(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_mesh(int argc, char **argv);
extern const char cmd_roster_usage[];
int cmd_roster(int argc, char **argv);
/* `crowdbake bake CATALOG.toml`, once cmd_bake has read its options. */
typedef struct cli_catalog_bake {
    const char *path;
    uint32_t jobs;
    bool force, quiet, json;
    const char *depfile, *manifest;
    const char *type, *fragment;       /* --type NAME: that type alone, and its manifest fragment */
    bool depfile_manifest_only;
    const cb_limits *limits;
    const cb_bake_settings *overrides; /* the command line's bake options, `override_fields` of them set */
    unsigned override_fields;          /* CB_BAKE_* */
    const char *syncs, *default_state; /* --sync STATE=speed|time,..., --default-state STATE */
    const cli_output *out;             /* -v: progress on stderr (as on a terminal) */
} cli_catalog_bake;
int cmd_bake_catalog(const cli_catalog_bake *options);

/* signals.c: the library's temporaries created where SIGINT, SIGTERM and SIGHUP handlers find
 * and remove them; an interrupted command then ends by the same signal. */
void cli_remove_temporaries_on_signals(void);

extern const char cmd_info_usage[], cmd_sample_usage[], cmd_bake_usage[], cmd_inspect_usage[], cmd_vat_usage[],
    cmd_report_usage[], cmd_verify_usage[], cmd_preview_usage[], cmd_mesh_usage[];

#endif
