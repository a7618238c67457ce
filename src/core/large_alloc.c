/* large_alloc.c - buffers of many megabytes (palettes, their pre-encoding rows, model files)
 * on transparent huge pages where the OS offers them: filling 57 MB takes 14,000 page faults
 * in 4 KB pages and 28 in 2 MB ones, which in a VM is a third of a bake's sampling time. */
#define _DEFAULT_SOURCE /* madvise, posix_memalign */
#include "crowdbake/core.h"
#include "internal/plumbing.h"

#include <stdlib.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(__linux__)
#include <sys/mman.h>
#endif

#define HUGE_PAGE ((size_t)2 << 20)

/* Under AddressSanitizer the heap is the sanitizer's, not glibc's: glibc's arenas are never set up,
 * and two threads' first malloc_trim race to set them up (glibc marks them set up before it has: a
 * SEGV in mtrim seen in a catalog bake's two types). There is nothing of glibc's to trim there. */
#if defined(__SANITIZE_ADDRESS__)
#define CB_GLIBC_HEAP 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CB_GLIBC_HEAP 0
#endif
#endif
#if !defined(CB_GLIBC_HEAP) && defined(__GLIBC__)
#define CB_GLIBC_HEAP 1
#elif !defined(CB_GLIBC_HEAP)
#define CB_GLIBC_HEAP 0
#endif

void *cb_alloc_large(size_t bytes)
{
    /* From half a huge page on, whole huge pages: the last one, partly used, counts 2 MB resident
     * once touched, where in 4 KB pages its part would take up to 511 page faults of fresh
     * memory, about 3 us each in a VM (the big rig's 14 MB stash: 1.7 MB of them; a measuring
     * thread's 1.4 MB scratch: 350). */
    if (bytes < HUGE_PAGE / 2) return malloc(bytes ? bytes : 1);
    size_t rounded = (bytes + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
    if (rounded < bytes) return NULL; /* size_t overflow */
    void *p = NULL;
    if (posix_memalign(&p, HUGE_PAGE, rounded) != 0) return NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(p, rounded, MADV_HUGEPAGE); /* a hint */
#endif
    return p;
}

void cb_release_free_memory(void)
{
    /* Whole free pages inside the heap are released too (madvise), not only its top. */
#if CB_GLIBC_HEAP
    malloc_trim(0);
#endif
}
