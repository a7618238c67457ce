/* roster_cache.h - what preparing an animal type found (its clips, ground speeds, states, LODs,
 * inputs and warnings), kept as a small record beside its palette, so that a rebuild whose
 * inputs did not change decides "up to date" without loading or sampling anything.
 *
 * The record is keyed by the bytes of every file the type read, its resolved catalog entry,
 * its bake settings, the resource limits and the crowdbake version: any difference, or a record
 * that is damaged, from another version or unreadable, means the type is prepared again from
 * its model. A record only ever saves work; it never decides what is baked. */
#ifndef CB_ROSTER_CACHE_H
#define CB_ROSTER_CACHE_H

#include "roster/roster.h"

/* OUT_DIR/.NAME.prep: hidden beside the palettes, one per type. False when it does not fit
 * (then the type has no record). */
bool cb_prep_record_path(const cb_catalog_animal *an, char *out, size_t size);

/* The key of a type's preparation: false when an input cannot be read. */
bool cb_prep_key(const cb_catalog_animal *an, const cb_limits *limits, char *const *inputs, uint32_t input_count,
                 uint64_t *key);

/* The record of a prepared type (malloc'ed bytes); false when out of memory. */
bool cb_prep_record_encode(const cb_roster_type *t, uint64_t key, unsigned char **data, size_t *size);

/* Fills t's prepared fields from the record at `path` when it is intact and its key matches the
 * files as they are now. False otherwise, with t's prepared fields freed and cleared. */
bool cb_prep_record_load(const char *path, const cb_catalog_animal *an, const cb_limits *limits, cb_roster_type *t);

/* Fills t's prepared fields from a record's bytes when they are intact (the framing, its hash
 * and plausible counts), whatever the files are now; *key: the key it was written under. A
 * manifest fragment (roster_fragment.c) carries one. False leaves t to cb_prep_clear. */
bool cb_prep_record_decode(const unsigned char *data, size_t size, const cb_catalog_animal *an, cb_roster_type *t,
                           uint64_t *key);

/* Frees and clears what preparing filled in (clips, states, LODs, inputs, warnings, sizes). */
void cb_prep_clear(cb_roster_type *t);

#endif
