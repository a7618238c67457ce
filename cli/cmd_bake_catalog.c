/* cmd_bake_catalog.c - `crowdbake bake CATALOG.toml`: every animal type of a roster. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "catalog/catalog_toml.h"
#include "internal/json.h"
#include "report/report.h"
#include "roster/roster.h"
#include "cli.h"
#include "internal/plumbing.h"

static const char *outcome_name(cb_type_outcome o)
{
    return o == CB_TYPE_BAKED ? "baked" : o == CB_TYPE_UP_TO_DATE ? "up-to-date" : o == CB_TYPE_SHARED ? "shared" : "failed";
}

static void print_json(const cb_roster *r)
{
    cb_json j;
    cb_json_init(&j, stdout);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "catalog", r->catalog->path);
    cb_json_string(&j, "manifest", r->manifest_path);
    cb_json_int(&j, "baked", r->baked);
    cb_json_int(&j, "up_to_date", r->up_to_date);
    cb_json_int(&j, "shared", r->shared);
    cb_json_int(&j, "failed", r->failed);
    cb_json_array(&j, "types");
    for (uint32_t i = 0; i < r->type_count; ++i) {
        const cb_roster_type *t = &r->types[i];
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", t->animal->name);
        cb_json_string(&j, "outcome", outcome_name(t->outcome));
        if (t->outcome != CB_TYPE_FAILED) {
            cb_json_string(&j, "palette", roster_palette_path(t));
            cb_json_number(&j, "seconds", t->seconds);
        } else {
            char text[sizeof t->error.message + 32];
            cb_json_string(&j, "error", cli_error_text(&t->error, text, sizeof text));
        }
        cli_json_warnings(&j, &t->warnings);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_end(&j);
}

/* --type NAME: the catalog's view of that one type (its animals are the catalog's own). */
static cb_status pick_type(const cb_catalog *cat, const char *name, cb_catalog *one, cb_error *err)
{
    for (uint32_t i = 0; i < cat->animal_count; ++i)
        if (strcmp(cat->animals[i].name, name) == 0) {
            *one = *cat;
            one->animals = &cat->animals[i], one->animal_count = 1;
            return CB_OK;
        }
    const char *guess = cb_closest_name(name, (const char *const *)&cat->animals[0].name, cat->animal_count,
                                        sizeof cat->animals[0]);
    return cb_fail(err, CB_ERR_SETTINGS, "%s has no animal type '%s'%s%s%s", cat->path, name, guess ? "; did you mean '" : "",
                   guess ? guess : "", guess ? "'?" : "");
}

int cmd_bake_catalog(const cli_catalog_bake *o)
{
    const char *path = o->path;
    uint32_t jobs = o->jobs;
    bool quiet = o->quiet, json = o->json;
    cb_error err = {0};
    cb_catalog cat;
    if (cb_catalog_load_checking(path, o->type, &cat, &err)) return cli_report(&err);
    if (cb_catalog_override_bake(&cat, o->overrides, o->override_fields, &err) ||
        cb_catalog_override_states(&cat, o->syncs, o->default_state, &err)) {
        cb_catalog_free(&cat);
        return cli_report(&err);
    }
    cb_catalog whole = cat; /* --type: cat becomes the one type's view; whole is freed */
    if (o->type && pick_type(&whole, o->type, &cat, &err)) {
        cb_catalog_free(&whole);
        return cli_report(&err);
    }
    char fragment_path[4096] = "";
    if (o->type) /* beside the type's palette */
        snprintf(fragment_path, sizeof fragment_path, "%s/%s.fragment", cat.animals[0].bake.out_dir, cat.animals[0].name);
    cb_roster_fragment fragment = {o->fragment ? o->fragment : fragment_path, o->syncs, o->default_state};
    cb_roster_options opt = {0};
    opt.fragment = o->type ? &fragment : NULL;
    opt.setting_name = cli_setting_flag;
    opt.jobs = jobs;
    opt.force = o->force;
    opt.log = quiet || json ? NULL : stdout;
    opt.tty = opt.log && isatty(fileno(stdout));
    /* Progress on stderr, on a terminal or with -v (never -q): where stdout does not show the log
     * as it goes (--json, or stdout piped) - a terminal's log has its own progress line. */
    if ((json || !opt.tty) && cli_progress(o->out)) opt.progress = stderr;
    cli_verbose(o->out, "%s: %u animal type%s, %u thread%s", path, cat.animal_count, cat.animal_count == 1 ? "" : "s", jobs,
                jobs == 1 ? "" : "s");
    opt.depfile = o->depfile;
    opt.depfile_manifest_only = o->depfile_manifest_only;
    char tool[4096];
    cli_executable(tool, sizeof tool);
    opt.tool = tool;
    opt.manifest = o->manifest;
    opt.limits = o->limits;
    cb_roster r;
    if (opt.log) printf("crowdbake: baking %u animal type%s from %s on %u thread%s\n", cat.animal_count,
                        cat.animal_count == 1 ? "" : "s", path, jobs,
                        jobs == 1 ? "" : "s");
    cb_status rc = cb_roster_bake(&cat, &opt, &r, &err);
    for (uint32_t i = 0; quiet && !json && i < r.type_count; ++i) /* the log showed none of them */
        cli_print_warnings(&r.types[i].warnings, false);
    if (json) print_json(&r);
    else if (!quiet) {
        printf("crowdbake: %u baked, %u up to date, %u sharing a palette, %u failed; %s %s%s\n", r.baked, r.up_to_date,
               r.shared, r.failed, o->type ? "fragment" : "manifest", r.manifest_path,
               r.manifest_written || o->type ? "" : " (unchanged)");
        cb_report rep;
        cb_error rerr = {0};
        /* Sizes of nothing ("0 types ... 0.0x") say nothing: with every type failed, the log and
         * the exit code have said it all. */
        if (r.failed < r.type_count && !cb_report_build(&cat, &r, &rep, &rerr)) {
            cb_report_paragraph(stdout, &rep);
            cb_report_free(&rep);
        }
    }
    if (rc && r.failed > 1) /* every failure was listed; the exit message names the first */
        fprintf(stderr, "crowdbake: %u animal types failed\n", r.failed);
    cb_roster_free(&r);
    cb_catalog_free(&whole);
    return rc ? cli_report(&err) : 0;
}
