/* key_scan.h - the pre-scan of cb_model_validate (model_validate.c): whole channels of
 * animation keys checked without branching, so clean ones (most of a real file) skip the
 * key-by-key check. Private to libcrowdbake; tests/lib/test_validate_keys.c checks them against
 * scalar references. */
#ifndef CB_KEY_SCAN_H
#define CB_KEY_SCAN_H

#include "crowdbake/core.h"

#include <stdbool.h>
#include <stdint.h>

/* Floats per key value of a channel's path. */
static inline int cb_path_components(cb_path p) { return p == CB_PATH_ROTATION ? 4 : 3; }

bool cb_floats_finite(const float *v, uint64_t n);
bool cb_times_increasing(const float *times, uint64_t n);
bool cb_rotations_unit(const float *q, uint64_t count, uint32_t stride);
/* Whether two channels of a clip share their key times (checked once for both). */
bool cb_same_key_times(const cb_channel *a, const cb_channel *b);
/* good[first[a] + c]: channel c of clip a needs no key-by-key check. On several threads for
 * large files; each flag depends on its channel alone. */
void cb_scan_channel_keys(const cb_model *m, const uint32_t *first, bool *good);

#endif
