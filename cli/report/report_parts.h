/* report_parts.h - what the report's renderings share (private to libcrowdbake): report.c
 * renders the terminal, Markdown and JSON forms, report_html.c the HTML page. */
#ifndef CB_REPORT_PARTS_H
#define CB_REPORT_PARTS_H

#include "internal/json.h"
#include "report/report.h"

/* The limits a type breaks, "; "-separated, or "". */
const char *report_limit_warnings(const cb_report_type *t, char *buf, size_t size);
/* What a type's row says beside its numbers: the palette it shares, the limits it breaks. */
const char *report_notes(const cb_report_type *t, char *buf, size_t size);
/* "qpos/u16", "qpos/u16 local": the palette's layout, precision and (local rows) bone space. */
const char *report_encoding(const cb_report_type *t, char *buf, size_t size);
/* Whether the type's rows can be held in that encoding: local rows only in qpos with u16 or float. */
bool report_encoding_holds(const cb_report_type *t, int layout, int precision);
/* Some type of the roster has local rows. */
bool report_has_local_rows(const cb_report *r);
/* a / b, 0 when b is 0. */
double report_ratio(uint64_t a, uint64_t b);
/* The roster's total against its budget: the verdict alone on its line (`bold` wraps it,
 * `line_end` ends it: "\n", Markdown's "  \n", HTML's "<br>"), then the VAT comparison. */
void report_budget_line(FILE *f, const cb_report *r, const char *bold, const char *line_end);
/* The foot-sync section (report_gaits.c): the gaits of a type, its warnings, and each rendering. */
void report_fill_gaits(const cb_roster_type *rt, cb_report_type *t);
uint32_t report_gait_warnings(const cb_report_type *t);
void report_gaits_text(FILE *f, const cb_report *r);
void report_gaits_markdown(FILE *f, const cb_report *r);
void report_gaits_json(cb_json *j, const cb_report_type *t);
/* The page's warnings, out of the advice column: each type's broken limits, and each sliding
 * gait once per clip with how many types' states play it. */
void report_warnings_html(FILE *f, const cb_report *r);
/* The herds section (report_herd.c): per type, the instances the budget left holds and the
 * vertices a frame they skin. */
void report_herds_text(FILE *f, const cb_report *r);
/* A count in three digits and an SI prefix: "83.4 G". */
const char *report_count_text(double n, char *buf, size_t size);
void report_herds_json(cb_json *j, const cb_report *r, const cb_report_type *t);
void report_vertex_rate_json(cb_json *j, const cb_report *r);
/* The share of the target's estimated vertex rate at 60 Hz that the type's herd skins; 0 where it states none. */
double report_frame_share(const cb_report *r, const cb_report_type *t);
double report_rate_instances(const cb_report *r, const cb_report_type *t);
void report_herds_html(FILE *f, const cb_report *r);
/* Writes s with HTML's special characters escaped (report_html.c, report_runtime.c). */
void report_html_escape(FILE *f, const char *s);

#endif
