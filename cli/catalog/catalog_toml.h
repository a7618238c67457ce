/* catalog_toml.h - reads an animal catalog (catalog.example.toml documents every key). */
#ifndef CB_CATALOG_TOML_H
#define CB_CATALOG_TOML_H

#include "catalog.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills *out (free with cb_catalog_free). Errors read "FILE:LINE:COLUMN: what is wrong; fix". */
cb_status cb_catalog_load(const char *path, cb_catalog *out, cb_error *err);
/* Same from text, for tests and fuzzing; `path` names it in messages and anchors relative paths. */
cb_status cb_catalog_parse(const char *text, size_t size, const char *path, cb_catalog *out, cb_error *err);

#ifdef __cplusplus
}
#endif

#endif
