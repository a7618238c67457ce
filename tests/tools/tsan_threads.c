/* tsan_threads.c - C11 threads on POSIX threads, preloaded into ThreadSanitizer runs only
 * (tests/tools/tsan_check.py; LD_PRELOAD=build/tsan/libtsan_threads.so).
 *
 * glibc implements thrd_create, mtx_* and cnd_* by calling its pthread functions internally,
 * where GCC 12's ThreadSanitizer cannot intercept them: a thread made with thrd_create crashes
 * the runtime at its first access (it never learnt of the thread), and a lock or a condition
 * would order nothing in its eyes. These definitions, loaded before libc, call the public
 * pthread functions that it does intercept. Types: glibc's mtx_t and cnd_t are unions the size
 * and alignment of pthread_mutex_t and pthread_cond_t, made for exactly this (threads.h). */
#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <threads.h>

_Static_assert(sizeof(mtx_t) == sizeof(pthread_mutex_t), "mtx_t is a pthread_mutex_t");
_Static_assert(sizeof(cnd_t) == sizeof(pthread_cond_t), "cnd_t is a pthread_cond_t");
_Static_assert(sizeof(thrd_t) == sizeof(pthread_t), "thrd_t is a pthread_t");

typedef struct start {
    thrd_start_t run;
    void *arg;
} start;

static void *started(void *p)
{
    start s = *(start *)p;
    free(p);
    return (void *)(intptr_t)s.run(s.arg);
}

static int status(int rc) { return rc == 0 ? thrd_success : rc == ENOMEM ? thrd_nomem : thrd_error; }

int thrd_create(thrd_t *thread, thrd_start_t run, void *arg)
{
    start *s = malloc(sizeof *s);
    if (!s) return thrd_nomem;
    *s = (start){run, arg};
    pthread_t id;
    int rc = pthread_create(&id, NULL, started, s);
    if (rc) free(s);
    else *thread = (thrd_t)id;
    return status(rc);
}

int thrd_join(thrd_t thread, int *result)
{
    void *r;
    int rc = pthread_join((pthread_t)thread, &r);
    if (!rc && result) *result = (int)(intptr_t)r;
    return status(rc);
}

int mtx_init(mtx_t *m, int type)
{
    if (type != mtx_plain) return thrd_error; /* the one kind crowdbake makes */
    return status(pthread_mutex_init((pthread_mutex_t *)m, NULL));
}
int mtx_lock(mtx_t *m) { return status(pthread_mutex_lock((pthread_mutex_t *)m)); }
int mtx_unlock(mtx_t *m) { return status(pthread_mutex_unlock((pthread_mutex_t *)m)); }
void mtx_destroy(mtx_t *m) { pthread_mutex_destroy((pthread_mutex_t *)m); }

int cnd_init(cnd_t *c) { return status(pthread_cond_init((pthread_cond_t *)c, NULL)); }
int cnd_wait(cnd_t *c, mtx_t *m) { return status(pthread_cond_wait((pthread_cond_t *)c, (pthread_mutex_t *)m)); }
int cnd_signal(cnd_t *c) { return status(pthread_cond_signal((pthread_cond_t *)c)); }
int cnd_broadcast(cnd_t *c) { return status(pthread_cond_broadcast((pthread_cond_t *)c)); }
void cnd_destroy(cnd_t *c) { pthread_cond_destroy((pthread_cond_t *)c); }
