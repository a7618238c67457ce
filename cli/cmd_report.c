/* cmd_report.c - `crowdbake report CATALOG.toml`: palette vs VAT bytes and the VRAM budget. */
#define _GNU_SOURCE /* open_memstream */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "../formats/atomic_file.h"
#include "../formats/catalog_toml.h"
#include "../formats/report.h"
#include "cli.h"

const char cmd_report_usage[] =
    "usage: crowdbake report CATALOG.toml [--json | --markdown] [--html FILE] [--no-fail] [-j N]\n\n"
    "Brings the roster's palettes up to date (as 'crowdbake bake' does), then reports per animal type\n"
    "the exact palette bytes, every layout x precision side by side, vertex-animation-texture bytes\n"
    "for three encodings with their ratio to the palette, the mesh buffers, measured errors, texture\n"
    "and bone limits, and the roster total against the catalog's [budget] (docs/budget.md).\n"
    "Exit code 3 when the roster exceeds its budget, unless --no-fail.\n";

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
    const char *path = NULL, *html = NULL, *jobs_text = NULL;
    bool json = false, markdown = false, no_fail = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json},      {"--markdown", NULL, NULL, &markdown},
                                  {"--html", "FILE", &html, NULL},    {"--no-fail", NULL, NULL, &no_fail},
                                  {"-j", "N", &jobs_text, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &path, 1, 1, &help);
    if (help) return fputs(cmd_report_usage, stdout), 0;
    if (rc) return rc;
    if (json && markdown) return cli_usage_error("report", "choose --json or --markdown");
    unsigned jobs = (unsigned)sysconf(_SC_NPROCESSORS_ONLN);
    if (jobs_text && (!cli_parse_u32(jobs_text, &jobs) || jobs < 1 || jobs > 64)) return cli_usage_error("report", "-j wants 1..64");
    cb_error err = {0};
    cb_catalog cat;
    if (cb_catalog_load(path, &cat, &err)) return cli_report(&err);
    cb_roster_options opt = {0};
    opt.jobs = jobs;
    opt.measure_vat = true;
    cb_roster roster;
    cb_status bake = cb_roster_bake(&cat, &opt, &roster, &err);
    if (bake) { /* report what baked; say what did not */
        for (uint32_t i = 0; i < roster.type_count; ++i)
            if (roster.types[i].outcome == CB_TYPE_FAILED)
                fprintf(stderr, "crowdbake: %s: %s\n", roster.types[i].animal->name, roster.types[i].error.message);
    }
    cb_report r;
    cb_error rerr = {0};
    if (!cb_report_build(&cat, &roster, &r, &rerr)) {
        if (json) cb_report_json(stdout, &r);
        else if (markdown) cb_report_markdown(stdout, &r);
        else cb_report_text(stdout, &r);
        if (html) write_html(html, &r, &rerr);
    }
    int status = rerr.status ? cli_report(&rerr) : bake ? (int)bake : 0;
    if (!status && r.over_budget && !no_fail) {
        fprintf(stderr, "crowdbake: the roster exceeds its budget (%s); exit 3 (use --no-fail to only report)\n", r.target);
        status = CB_ERR_BUDGET;
    }
    if (!rerr.status) cb_report_free(&r);
    cb_roster_free(&roster);
    cb_catalog_free(&cat);
    return status;
}
