// catalog_canonical.h - an animal's canonical words (the roster's input key hashes them).
#ifndef CB_CATALOG_CANONICAL_H
#define CB_CATALOG_CANONICAL_H

#include <string>

#include "catalog/catalog.h"

// Every setting of `an` that changes its bake, as one line; paths relative to the catalog's folder
// `dir`, so the line holds no absolute path the catalog did not write.
std::string catalog_canonical_words(const char *dir, const cb_catalog_animal *an);

#endif
