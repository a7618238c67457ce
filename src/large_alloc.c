/* large_alloc.c - buffers of many megabytes (palettes, their pre-encoding rows, model files)
 * on transparent huge pages where the OS offers them: filling 57 MB takes 14,000 page faults
 * in 4 KB pages and 28 in 2 MB ones, which in a VM is a third of a bake's sampling time. */
#define _DEFAULT_SOURCE /* madvise, posix_memalign */
#include "crowdbake/core.h"

#include <stdlib.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(__linux__)
#include <sys/mman.h>
#endif

#define HUGE_PAGE ((size_t)2 << 20)

void *cb_alloc_large(size_t bytes)
{
    if (bytes < HUGE_PAGE) return malloc(bytes ? bytes : 1);
    void *p = NULL;
    if (posix_memalign(&p, HUGE_PAGE, bytes) != 0) return NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    /* A hint, for the whole huge pages only: a partly used one would count 2 MB resident. */
    madvise(p, bytes / HUGE_PAGE * HUGE_PAGE, MADV_HUGEPAGE);
#endif
    return p;
}

void cb_release_free_memory(void)
{
    /* Whole free pages inside the heap are released too (madvise), not only its top. */
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}
