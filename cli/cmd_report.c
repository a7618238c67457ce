/* cmd_report.c - `crowdbake report CATALOG.toml|MODEL`: palette vs VAT bytes and the VRAM budget. */
#define _GNU_SOURCE /* open_memstream */
#include <ctype.h>
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "internal/atomic_file.h"
#include "catalog/catalog_toml.h"
#include "report/report.h"
#include "cli.h"

const char cmd_report_usage[] =
    "usage: crowdbake report CATALOG.toml|MODEL [--target NAME] [--json | --markdown] [--html FILE] [--no-fail] [-j N]\n"
    "                        [--out-dir DIR] [-v|-q]\n\n"
    "Brings the roster's palettes up to date (as 'crowdbake bake' does; a single MODEL is baked with\n"
    "the default settings into a temporary folder), then reports per animal type\n"
    "the exact palette bytes, every layout x precision side by side, vertex-animation-texture bytes\n"
    "for three encodings with their ratio to the palette, the mesh buffers, measured errors, texture\n"
    "and bone limits, and the roster total against the catalog's [budget] (docs/budget.md); then per\n"
    "type its runtime meshes (crowdbake mesh --quantize: the model at 4, 2 and 1 influences and each LOD\n"
    "at its lod_max_influences, with bytes and extra error), a batch of 100 copies against instancing,\n"
    "and the bytes pre-baked transitions between loops would take that a runtime cross-fade saves.\n"
    "  --target NAME   the budget's target profile (docs/budget.md): replaces the catalog's\n"
    "                  [budget] target; for a MODEL, the only way to give one\n"
    "  --out-dir DIR   a catalog's palettes are brought up to date there, not in its out_dir\n"
    "  -v, --verbose   a line per type on stderr as it is baked and as its runtime meshes are measured\n"
    "                  (the default on a terminal)\n"
    "  -q, --quiet     no progress lines\n"
    "Exit code 3 when the roster exceeds its budget, unless --no-fail.\n";

/* s as a TOML basic string. */
static void toml_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"' || *s == '\\') fprintf(f, "\\%c", *s);
        else if ((unsigned char)*s < 0x20) fprintf(f, "\\u%04x", (unsigned char)*s);
        else fputc(*s, f);
    }
    fputc('"', f);
}

/* A catalog of one animal type: the model, named after its file, baked with the defaults into
 * `out_dir`. Parsed from text so the model gets exactly a catalog's checks and settings. */
static cb_status single_model_catalog(const char *model, const char *out_dir, cb_catalog *cat, cb_error *err)
{
    char name[64] = "", *text = NULL;
    const char *base = strrchr(model, '/') ? strrchr(model, '/') + 1 : model;
    size_t n = 0;
    for (const char *c = base; *c && *c != '.' && n + 1 < sizeof name; ++c)
        name[n++] = isalnum((unsigned char)*c) || *c == '-' ? *c : '_';
    if (!n) name[n++] = 'm';
    name[n] = '\0';
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    fputs("[bake]\nout_dir = ", f);
    toml_string(f, out_dir);
    /* Sized as the default bake would be; a clip over its error budget is a warning here (the
     * bake of the model says what would meet it), not a report that cannot be made. */
    fputs("\nallow_over_budget = true", f);
    fprintf(f, "\n[animal.%s]\nmodel = ", name);
    toml_string(f, base); /* relative to the "catalog", which is the model itself */
    fputc('\n', f);
    fclose(f);
    cb_status rc = cb_catalog_parse(text, size, model, cat, err);
    free(text);
    return rc;
}

/* Removes the temporary folder of a single-model report and what the bake wrote in it. */
static void remove_folder(const char *dir)
{
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        unlink(path);
    }
    if (d) closedir(d);
    rmdir(dir);
}

/* A single model as a catalog baked into a new temporary folder (in tmp). The model is loaded
 * once up front so a broken one is reported as itself, not as an entry of the catalog made for
 * it. On failure nothing is left behind. */
static cb_status open_single_model(const char *path, char *tmp, size_t tmp_size, cb_catalog *cat, cb_error *err)
{
    cb_limits limits = cb_default_limits();
    cb_model *m = cli_load_model(NULL, path, &limits, err);
    if (m && cli_pick_skin(m, NULL, err) < 0) cb_model_free(m), m = NULL;
    if (!m) return err->status;
    cb_model_free(m);
    const char *dir = getenv("TMPDIR") && *getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
    snprintf(tmp, tmp_size, "%s/crowdbake-report-XXXXXX", dir);
    if (!mkdtemp(tmp)) return cb_fail(err, CB_ERR_IO, "%s: cannot create a temporary folder for the bake (set TMPDIR)", tmp);
    /* Absolute: the catalog made for the model resolves out_dir from the model's folder, so a
     * relative TMPDIR would bake beside the model (and be left there), not where it was made. */
    char abs[PATH_MAX];
    if (!realpath(tmp, abs) || strlen(abs) >= tmp_size) {
        rmdir(tmp);
        return cb_fail(err, CB_ERR_IO, "%s: cannot resolve the temporary folder's path (set TMPDIR to an absolute path)", tmp);
    }
    memcpy(tmp, abs, strlen(abs) + 1);
    if (single_model_catalog(path, tmp, cat, err)) remove_folder(tmp);
    return err->status;
}

/* --target: a built-in profile by name replaces the [budget] target; its memory and texture
 * limit come with it, the catalog's crowd_share and max_bones stay. */
static void apply_target(cb_catalog *cat, const char *target)
{
    cat->budget.set = true;
    cat->budget.target = target;
    cat->budget.vram_bytes = 0;
    cat->budget.max_texture_size = 0;
    cat->budget.pos = (cb_source_pos){0, 0}; /* no place in the catalog: messages name --target */
    if (!(cat->budget.crowd_share > 0)) cat->budget.crowd_share = 1;
    if (!cat->budget.max_bones) cat->budget.max_bones = 256;
}

static cb_status write_html(const char *path, const cb_report *r, cb_error *err)
{
    char *buf = NULL;
    size_t size = 0;
    FILE *mem = open_memstream(&buf, &size);
    if (!mem) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    cb_report_html(mem, r);
    fclose(mem);
    cb_atomic_file f;
    cb_status rc = cb_atomic_open(&f, path, err);
    if (!rc) rc = cb_atomic_write(&f, buf, size, err);
    if (!rc) rc = cb_atomic_commit(&f, err);
    else cb_atomic_abort(&f);
    free(buf);
    return rc;
}

int cmd_report(int argc, char **argv)
{
    cli_output out;
    if (cli_take_output(&argc, argv, &out)) return CLI_EXIT_USAGE;
    const char *path = NULL, *html = NULL, *jobs_text = NULL, *target = NULL, *out_dir = NULL;
    bool json = false, markdown = false, no_fail = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json},      {"--markdown", NULL, NULL, &markdown},
                                  {"--html", "FILE", &html, NULL},    {"--no-fail", NULL, NULL, &no_fail},
                                  {"-j", "N", &jobs_text, NULL},      {"--target", "NAME", &target, NULL},
                                  {"--out-dir", "DIR", &out_dir, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &path, 1, 1, &help);
    if (help) return fputs(cmd_report_usage, stdout), 0;
    if (rc) return rc;
    if (json && markdown) return cli_usage_error("report", "choose --json or --markdown");
    unsigned jobs = (unsigned)sysconf(_SC_NPROCESSORS_ONLN);
    if (jobs_text && (!cli_parse_u32(jobs_text, &jobs) || jobs < 1 || jobs > 64)) return cli_usage_error("report", "-j wants 1..64");
    cb_error err = {0};
    cb_catalog cat;
    char tmp[4096] = "";
    const char *ext = strrchr(path, '.');
    /* By its first bytes (a model, or a palette that loading a model refuses with the fix), else by its name; the rest
     * is a catalog (TOML starts with no magic of its own). */
    cli_file_kind kind = cli_file_kind_of(path);
    bool model = (kind != CLI_FILE_UNKNOWN && kind != CLI_FILE_MISSING) ||
                 (ext && (strcasecmp(ext, ".glb") == 0 || strcasecmp(ext, ".gltf") == 0));
    if (model ? open_single_model(path, tmp, sizeof tmp, &cat, &err) : cb_catalog_load(path, &cat, &err))
        return cli_report(&err);
    if (target) apply_target(&cat, target);
    if (out_dir && !model) { /* the palettes the report bakes go there (a build action's own folder) */
        cb_bake_settings over = cat.defaults;
        over.out_dir = out_dir;
        if (cb_catalog_override_bake(&cat, &over, CB_BAKE_OUT_DIR, &err)) {
            cb_catalog_free(&cat);
            return cli_report(&err);
        }
    }
    cb_roster_options opt = {0};
    opt.setting_name = cli_setting_flag;
    opt.jobs = jobs;
    opt.measure_vat = true;
    /* The bake takes seconds (7 s for three animals): a line per type on stderr as each is
     * done, on a terminal or with -v, never with -q; stdout keeps only the report. */
    bool progress = cli_progress(&out);
    opt.log = progress ? stderr : NULL;
    opt.tty = progress && isatty(STDERR_FILENO);
    cb_roster roster;
    cb_status bake = cb_roster_bake(&cat, &opt, &roster, &err);
    if (bake) { /* report what baked; say what did not */
        for (uint32_t i = 0; i < roster.type_count; ++i)
            if (roster.types[i].outcome == CB_TYPE_FAILED) {
                char text[sizeof err.message + 32];
                fprintf(stderr, "crowdbake: %s: %s\n", roster.types[i].animal->name,
                        cli_error_text(&roster.types[i].error, text, sizeof text));
            }
    }
    cb_report r;
    cb_error rerr = {0};
    if (!cb_report_build(&cat, &roster, &r, &rerr)) {
        r.single_model = model;
        /* then a line per type as its runtime meshes are measured: seconds more, which the log
         * alone left silent (stdout redirected, the report still to come) */
        cb_report_add_runtime(&roster, &r, opt.log);
        if (json) cb_report_json(stdout, &r);
        else if (markdown) cb_report_markdown(stdout, &r);
        else cb_report_text(stdout, &r);
        if (html) write_html(html, &r, &rerr);
    }
    int status = rerr.status ? cli_report(&rerr) : bake ? cli_exit_code(bake) : 0;
    if (!status && r.over_budget && !no_fail) {
        fprintf(stderr, "crowdbake: the roster exceeds its budget (%s); exit 3 (use --no-fail to only report)\n", r.target);
        status = CLI_EXIT_BUDGET;
    }
    if (!rerr.status) cb_report_free(&r);
    cb_roster_free(&roster);
    cb_catalog_free(&cat);
    if (model) remove_folder(tmp);
    return status;
}
