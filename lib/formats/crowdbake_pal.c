/* crowdbake_pal.c - the reader's implementation, compiled once into libcrowdbake. */
#define CBPAL_WITH_ZSTD
#define CROWDBAKE_PAL_IMPLEMENTATION
#include "crowdbake_pal.h"
