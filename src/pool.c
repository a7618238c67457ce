/* pool.c - see pool.h. */
#include "pool.h"

#include <stdbool.h>
#include <threads.h>

typedef struct share {
    void (*work)(void *ctx, uint32_t thread, uint32_t threads);
    void *ctx;
    uint32_t thread, threads;
} share;

static int share_main(void *arg)
{
    share *s = arg;
    s->work(s->ctx, s->thread, s->threads);
    return 0;
}

void cb_pool_run(uint32_t threads, void (*work)(void *ctx, uint32_t thread, uint32_t threads), void *ctx)
{
    if (threads < 1) threads = 1;
    if (threads > CB_POOL_MAX_THREADS) threads = CB_POOL_MAX_THREADS;
    share shares[CB_POOL_MAX_THREADS];
    thrd_t ids[CB_POOL_MAX_THREADS];
    bool started[CB_POOL_MAX_THREADS] = {false};
    for (uint32_t t = 0; t < threads; ++t) {
        shares[t] = (share){work, ctx, t, threads};
        started[t] = t > 0 && thrd_create(&ids[t], share_main, &shares[t]) == thrd_success;
    }
    share_main(&shares[0]);
    for (uint32_t t = 1; t < threads; ++t) {
        if (started[t]) thrd_join(ids[t], NULL);
        else share_main(&shares[t]); /* no thread: do its share here */
    }
}
