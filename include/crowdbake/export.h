/* export.h - CROWDBAKE_API marks what libcrowdbake exports. The library is built with
 * -fvisibility=hidden and a version script (src/libcrowdbake.map), so its shared object exports
 * exactly the functions and objects its installed headers declare with this mark, nothing else
 * (tests/tools/abi_symbols.py checks the installed library). */
#ifndef CROWDBAKE_EXPORT_H
#define CROWDBAKE_EXPORT_H

#if defined(__GNUC__) || defined(__clang__)
#define CROWDBAKE_API __attribute__((visibility("default")))
#else
#define CROWDBAKE_API
#endif

#endif
