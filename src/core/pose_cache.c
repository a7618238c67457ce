/* pose_cache.c - see pose_cache.h. An open-addressed table of time bits to pose numbers, the
 * poses in blocks that never move (so a pointer handed out stays valid as the cache grows). A
 * block is a huge page where the OS offers them (cb_alloc_large): in a VM each fresh 4 KB page
 * costs a fault, and a search touches megabytes. */
#include "pose_cache.h"

#include "crowdbake/core.h" /* cb_alloc_large */
#include "internal/plumbing.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>

/* Worst points kept (a search probes a clip at a handful of rates and kinds of rows). */
enum { POSE_WORST_KEPT = 16 };

#define BLOCK_BYTES ((size_t)2 << 20) /* a huge page */
#define CHUNK_BYTES ((size_t)256 << 10) /* an arena's block: an eighth of a huge page */

struct pose_arena {
    mtx_t lock;
    char *page;          /* the page chunks are cut from, or NULL */
    size_t used;         /* its bytes handed out */
    void **pages;        /* every page (and every block too big for one), freed with the arena */
    uint32_t page_count;
    void **spare;        /* chunks handed back (pose_cache_release_poses), each spare_bytes: taken first */
    size_t spare_bytes;
    uint32_t spare_count, spare_room;
};

struct pose_cache {
    uint32_t bones, extra;
    size_t stride;          /* doubles a pose: its matrices and its extra */
    uint32_t count, limit;  /* poses kept, and the most max_bytes allows */
    uint64_t *keys;         /* the table: a time's bits, or EMPTY */
    uint32_t *slots;        /* the table: its pose's number */
    uint32_t capacity;      /* table entries, a power of two, at least twice count */
    double **blocks;        /* block_poses poses each */
    pose_arena *arena;      /* where they come from, or NULL: its own, freed with it */
    uint32_t block_count, block_poses;
    void *attached[POSE_CACHE_SLOTS]; /* its user's blocks for the same clip (pose_cache_attach), or NULL */
    void *analysis;         /* and the clip's analysis (pose_cache_attach_analysis), or NULL */
    pose_worst worst[POSE_WORST_KEPT]; /* pose_cache_note_worst's, the newest at worst_count - 1 (mod) */
    uint32_t worst_count;
};

/* No time's bits: the pattern of a NaN with a payload no arithmetic produces. */
#define EMPTY UINT64_C(0xFFFFFFFFFFFFFFFF)

static uint64_t time_bits(double t)
{
    uint64_t bits;
    memcpy(&bits, &t, sizeof bits);
    return bits;
}

/* The table entry holding bits, or the empty one where it would go. */
static uint32_t probe_entry(const pose_cache *c, uint64_t bits)
{
    /* Every bit of the time into the index: a product's bits 32 and up (as this took) see only
     * the time's bits below them, and a time that is a short binary fraction (0.5, 0.75, ...)
     * has none set there, so such times all fell on one entry and a find walked long runs
     * (Cow's search: 190 instructions a find). MurmurHash3's finalizer mixes both ways. */
    uint64_t h = bits ^ bits >> 33;
    h *= UINT64_C(0xFF51AFD7ED558CCD);
    h ^= h >> 33;
    uint32_t mask = c->capacity - 1, i = (uint32_t)h & mask;
    while (c->keys[i] != bits && c->keys[i] != EMPTY) i = (i + 1) & mask;
    return i;
}

static double *pose_at(const pose_cache *c, uint32_t n)
{
    return c->blocks[n / c->block_poses] + (n % c->block_poses) * c->stride;
}

pose_arena *pose_arena_create(void)
{
    pose_arena *a = calloc(1, sizeof *a);
    if (a && mtx_init(&a->lock, mtx_plain) != thrd_success) free(a), a = NULL;
    return a;
}

void pose_arena_free(pose_arena *a)
{
    if (!a) return;
    for (uint32_t i = 0; i < a->page_count; ++i) free(a->pages[i]);
    mtx_destroy(&a->lock);
    free(a->spare), free(a->pages), free(a);
}

/* Keeps block among the arena's pages (freed with them); false, block freed: out of memory. */
static bool arena_own(pose_arena *a, void *block)
{
    void **pages = block ? realloc(a->pages, (a->page_count + 1) * sizeof *pages) : NULL;
    if (!pages) return free(block), false;
    a->pages = pages, a->pages[a->page_count++] = block;
    return true;
}

/* bytes from the arena's page, a new page where it has too few left (a block over half a page:
 * its own); NULL when out of memory. */
static void *arena_take(pose_arena *a, size_t bytes)
{
    void *block = NULL;
    mtx_lock(&a->lock);
    if (a->spare_count && a->spare_bytes == bytes) {
        block = a->spare[--a->spare_count]; /* touched already: no page to clear */
    } else if (bytes > BLOCK_BYTES / 2) {
        block = cb_alloc_large(bytes);
        if (!arena_own(a, block)) block = NULL;
    } else {
        if (!a->page || BLOCK_BYTES - a->used < bytes) {
            char *page = cb_alloc_large(BLOCK_BYTES);
            if (arena_own(a, page)) a->page = page, a->used = 0;
        }
        if (a->page && BLOCK_BYTES - a->used >= bytes) block = a->page + a->used, a->used += bytes;
    }
    mtx_unlock(&a->lock);
    return block;
}

/* Keeps a chunk of `bytes` that a cache no longer needs for the next arena_take of as many
 * (every cache of a run cuts chunks of one size: one skin's poses); one of another size stays
 * unused until the arena is freed. */
static void arena_give(pose_arena *a, void *chunk, size_t bytes)
{
    mtx_lock(&a->lock);
    if (a->spare_count && a->spare_bytes != bytes) {
        mtx_unlock(&a->lock);
        return;
    }
    if (a->spare_count == a->spare_room) {
        uint32_t room = a->spare_room ? 2 * a->spare_room : 64;
        void **spare = realloc(a->spare, room * sizeof *spare);
        if (spare) a->spare = spare, a->spare_room = room;
    }
    if (a->spare_count < a->spare_room) a->spare[a->spare_count++] = chunk, a->spare_bytes = bytes;
    mtx_unlock(&a->lock);
}

pose_cache *pose_cache_create(uint32_t bones, uint32_t extra, size_t max_bytes)
{
    return pose_cache_create_in(NULL, bones, extra, max_bytes);
}

pose_cache *pose_cache_create_in(pose_arena *arena, uint32_t bones, uint32_t extra, size_t max_bytes)
{
    pose_cache *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->arena = arena;
    c->bones = bones ? bones : 1, c->extra = extra;
    c->stride = (size_t)c->bones * 16 + extra;
    size_t pose_bytes = c->stride * sizeof(double);
    size_t limit = max_bytes / pose_bytes;
    /* As many poses as fill a huge page (an arena's chunk) without passing it: a block a pose
     * over 2 MB took two (cb_alloc_large rounds up), and the few bytes past the first made the
     * kernel clear all of the second (Cow's search: 12 of its 24 blocks, 24 MB cleared for
     * 100 KB used). */
    size_t fit = (arena ? CHUNK_BYTES : BLOCK_BYTES) / pose_bytes;
    c->block_poses = (uint32_t)(fit ? fit : 1);
    c->limit = limit > UINT32_MAX / 4 ? UINT32_MAX / 4 : (uint32_t)limit;
    c->capacity = 64;
    c->keys = malloc(c->capacity * sizeof *c->keys);
    c->slots = malloc(c->capacity * sizeof *c->slots);
    if (!c->keys || !c->slots) {
        pose_cache_free(c);
        return NULL;
    }
    memset(c->keys, 0xFF, c->capacity * sizeof *c->keys);
    return c;
}

void pose_cache_free(pose_cache *c)
{
    if (!c) return;
    for (uint32_t b = 0; !c->arena && b < c->block_count; ++b) free(c->blocks[b]);
    for (int k = 0; k < POSE_CACHE_SLOTS; ++k) free(c->attached[k]);
    free(c->analysis), free(c->blocks), free(c->keys), free(c->slots), free(c);
}

const double *pose_cache_find(const pose_cache *c, double t)
{
    uint32_t i = probe_entry(c, time_bits(t));
    return c->keys[i] == EMPTY ? NULL : pose_at(c, c->slots[i]);
}

/* The table at twice its capacity, every entry placed again. False: out of memory (the table
 * as it was). */
static bool grow_table(pose_cache *c)
{
    pose_cache bigger = *c;
    bigger.capacity = c->capacity * 2;
    bigger.keys = malloc(bigger.capacity * sizeof *bigger.keys);
    bigger.slots = malloc(bigger.capacity * sizeof *bigger.slots);
    if (!bigger.keys || !bigger.slots) {
        free(bigger.keys), free(bigger.slots);
        return false;
    }
    memset(bigger.keys, 0xFF, bigger.capacity * sizeof *bigger.keys);
    for (uint32_t i = 0; i < c->capacity; ++i) {
        if (c->keys[i] == EMPTY) continue;
        uint32_t k = probe_entry(&bigger, c->keys[i]);
        bigger.keys[k] = c->keys[i], bigger.slots[k] = c->slots[i];
    }
    free(c->keys), free(c->slots);
    c->keys = bigger.keys, c->slots = bigger.slots, c->capacity = bigger.capacity;
    return true;
}

/* A block for pose number n where it has none yet. */
static bool ensure_block(pose_cache *c, uint32_t n)
{
    if (n / c->block_poses < c->block_count) return true;
    double **blocks = realloc(c->blocks, (c->block_count + 1) * sizeof *blocks);
    if (!blocks) return false;
    c->blocks = blocks;
    size_t bytes = c->block_poses * c->stride * sizeof(double);
    blocks[c->block_count] = c->arena ? arena_take(c->arena, bytes) : cb_alloc_large(bytes);
    if (!blocks[c->block_count]) return false;
    c->block_count++;
    return true;
}

double *pose_cache_add(pose_cache *c, double t)
{
    uint64_t bits = time_bits(t);
    if (bits == EMPTY || c->count >= c->limit) return NULL;
    if (2 * (c->count + 1) > c->capacity && !grow_table(c)) return NULL;
    if (!ensure_block(c, c->count)) return NULL;
    uint32_t i = probe_entry(c, bits);
    c->keys[i] = bits, c->slots[i] = c->count;
    double *pose = pose_at(c, c->count++);
    if (c->extra) pose[(size_t)c->bones * 16] = NAN; /* not derived yet */
    return pose;
}

void pose_cache_clear(pose_cache *c)
{
    c->count = 0;
    memset(c->keys, 0xFF, c->capacity * sizeof *c->keys);
    for (int k = 0; k < POSE_CACHE_SLOTS; ++k) free(c->attached[k]), c->attached[k] = NULL;
    free(c->analysis), c->analysis = NULL;
    c->worst_count = 0;
}

void pose_cache_release_poses(pose_cache *c)
{
    c->count = 0;
    memset(c->keys, 0xFF, c->capacity * sizeof *c->keys);
    if (!c->arena) return; /* its own blocks: kept for its next poses */
    size_t bytes = c->block_poses * c->stride * sizeof(double);
    for (uint32_t b = 0; b < c->block_count; ++b) arena_give(c->arena, c->blocks[b], bytes);
    c->block_count = 0;
}

void pose_cache_attach(pose_cache *c, int slot, void *block)
{
    free(c->attached[slot]);
    c->attached[slot] = block;
}

void *pose_cache_attached(const pose_cache *c, int slot) { return c->attached[slot]; }
void pose_cache_attach_analysis(pose_cache *c, void *block)
{
    free(c->analysis);
    c->analysis = block;
}
void *pose_cache_analysis(const pose_cache *c) { return c->analysis; }

uint32_t pose_cache_count(const pose_cache *c) { return c->count; }

/* The slot of the point kept for frames and parts, or POSE_WORST_KEPT. */
static uint32_t worst_slot(const pose_cache *c, uint32_t frames, uint32_t parts)
{
    uint32_t kept = c->worst_count < POSE_WORST_KEPT ? c->worst_count : POSE_WORST_KEPT;
    for (uint32_t i = 0; i < kept; ++i)
        if (c->worst[i].frames == frames && c->worst[i].parts == parts) return i;
    return POSE_WORST_KEPT;
}

void pose_cache_note_worst(pose_cache *c, pose_worst at)
{
    uint32_t i = worst_slot(c, at.frames, at.parts);
    if (i == POSE_WORST_KEPT) i = c->worst_count++ % POSE_WORST_KEPT;
    c->worst[i] = at;
}

bool pose_cache_worst(const pose_cache *c, uint32_t frames, uint32_t parts, pose_worst *at)
{
    uint32_t i = worst_slot(c, frames, parts);
    if (i < POSE_WORST_KEPT) *at = c->worst[i];
    return i < POSE_WORST_KEPT;
}
