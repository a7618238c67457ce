/* pool.h - the library's one way to run work on several threads (private to libcrowdbake). */
#ifndef CB_POOL_H
#define CB_POOL_H

#include <stdint.h>

/* Threads that run work(ctx, t, shares) for t = 0..shares-1, t = 0 on the calling thread and
 * the others on threads of their own, and return when every share is done. How the shares
 * split the work is the caller's: by a fixed stride when the result must not depend on timing,
 * or from a shared atomic counter.
 *
 * Work that comes in several runs one after the other (a bake's sampling, encoding and
 * measuring) keeps its threads: cb_pool_create(threads) starts threads - 1 of them (clamped to
 * CB_POOL_MAX_THREADS in all; NULL where none is needed or none starts), cb_pool_dispatch runs
 * one run's shares (clamped to 1..CB_POOL_MAX_THREADS; those without a thread, all of them with
 * a NULL pool, run on the caller after its own), and cb_pool_free stops the threads. Between
 * runs a thread keeps checking for the next one for a short while before it sleeps, as waking
 * a sleeping thread can take longer than a small run (on the VMs this was measured on, from
 * 50 us to over 1 ms). One caller dispatches at a time. cb_pool_run is one run on threads
 * started for it, which end with it (for a single run it measured faster than a pool). */
#define CB_POOL_MAX_THREADS 64
typedef struct cb_pool cb_pool;
cb_pool *cb_pool_create(uint32_t threads);
void cb_pool_dispatch(cb_pool *pool, uint32_t shares, void (*work)(void *ctx, uint32_t thread, uint32_t threads),
                      void *ctx);
void cb_pool_free(cb_pool *pool);
void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads), void *ctx);

#endif
