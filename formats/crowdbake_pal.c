/* crowdbake_pal.c - the reader's implementation, compiled once into libcrowdbake. */
#define CBPAL_WITH_ZSTD
#define CROWDBAKE_PAL_IMPLEMENTATION
/* The reader's functions are part of libcrowdbake's API (the library is built with hidden
 * visibility; its header stays free of any build's macros, for engines that compile it alone). */
#pragma GCC visibility push(default)
#include "crowdbake_pal.h"
#pragma GCC visibility pop
