/* fuzz_catalog.c - libFuzzer target: the TOML catalog parser and its validation. */
#include <stdint.h>

#include "catalog/catalog_toml.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cb_catalog cat;
    cb_error err = {0};
    if (cb_catalog_parse((const char *)data, size, "fuzz.toml", &cat, &err) == CB_OK) cb_catalog_free(&cat);
    return 0;
}
