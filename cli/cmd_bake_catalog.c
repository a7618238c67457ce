/* cmd_bake_catalog.c - `crowdbake bake CATALOG.toml`: every animal type of a roster. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "catalog/catalog_toml.h"
#include "crowdbake/json.h"
#include "report/report.h"
#include "roster/roster.h"
#include "cli.h"

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
            cb_json_string(&j, "palette", (t->animal->bake.formats & CB_FORMAT_PAL) ? t->pal_path : t->exr_path);
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

int cmd_bake_catalog(const cli_catalog_bake *o)
{
    const char *path = o->path;
    uint32_t jobs = o->jobs;
    bool quiet = o->quiet, json = o->json;
    cb_error err = {0};
    cb_catalog cat;
    if (cb_catalog_load(path, &cat, &err)) return cli_report(&err);
    if (cb_catalog_override_bake(&cat, o->overrides, o->override_fields, &err) ||
        cb_catalog_override_states(&cat, o->syncs, o->default_state, &err)) {
        cb_catalog_free(&cat);
        return cli_report(&err);
    }
    cb_roster_options opt = {0};
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
        printf("crowdbake: %u baked, %u up to date, %u sharing a palette, %u failed; manifest %s%s\n", r.baked, r.up_to_date,
               r.shared, r.failed, r.manifest_path, r.manifest_written ? "" : " (unchanged)");
        cb_report rep;
        cb_error rerr = {0};
        if (!cb_report_build(&cat, &r, &rep, &rerr)) {
            cb_report_paragraph(stdout, &rep);
            cb_report_free(&rep);
        }
    }
    if (rc && r.failed > 1) /* every failure was listed; the exit message names the first */
        fprintf(stderr, "crowdbake: %u animal types failed\n", r.failed);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
    return rc ? cli_report(&err) : 0;
}
