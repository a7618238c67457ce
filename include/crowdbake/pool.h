/* pool.h - run work on several threads, the library's way: what a program that bakes many
 * models at once (a catalog's types, `crowdbake bake CATALOG`) shares the library's threads with
 * instead of starting its own. */
#ifndef CROWDBAKE_POOL_H
#define CROWDBAKE_POOL_H

#include <stdint.h>

#include "export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Runs work(ctx, t, threads) for t = 0..threads-1 (threads clamped to 1..64), t = 0 on the
 * calling thread and the others on threads started for this run, and returns when every one is
 * done; a share whose thread cannot start runs on the caller after its own. How the shares split
 * the work is the caller's: by a fixed stride when the result must not depend on timing, or
 * from a shared atomic counter (then a failed start only leaves its part to the others). */
CROWDBAKE_API void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads),
                               void *ctx);

#ifdef __cplusplus
}
#endif

#endif
