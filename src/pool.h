/* pool.h - the library's one way to run work on several threads (private to libcrowdbake). */
#ifndef CB_POOL_H
#define CB_POOL_H

#include <stdint.h>

/* Runs work(ctx, t, threads) for t = 0..threads-1, t = 0 on the calling thread and the others
 * on threads of their own (a share whose thread cannot start runs on the caller afterwards),
 * and returns when every share is done. threads is clamped to 1..CB_POOL_MAX_THREADS. How the
 * shares split the work is the caller's: by a fixed stride when the result must not depend on
 * timing, or from a shared atomic counter. */
#define CB_POOL_MAX_THREADS 64
void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads), void *ctx);

#endif
