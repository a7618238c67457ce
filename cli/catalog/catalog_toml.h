/* catalog_toml.h - reads an animal catalog (catalog.example.toml documents every key). */
#ifndef CB_CATALOG_TOML_H
#define CB_CATALOG_TOML_H

#include "catalog.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills *out (free with cb_catalog_free). Errors read "FILE:LINE:COLUMN: what is wrong; fix". */
cb_status cb_catalog_load(const char *path, cb_catalog *out, cb_error *err);
/* As cb_catalog_load, checking that the model and LOD files exist for the animal named
 * `files_of` alone ("" for none; NULL: every animal): a build action that bakes one type, or
 * merges fragments, has only the files it needs (docs/bazel.md). */
cb_status cb_catalog_load_checking(const char *path, const char *files_of, cb_catalog *out, cb_error *err);
/* Same from text, for tests and fuzzing; `path` names it in messages and anchors relative paths. */
cb_status cb_catalog_parse(const char *text, size_t size, const char *path, cb_catalog *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
