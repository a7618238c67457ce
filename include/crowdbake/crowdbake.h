/* crowdbake.h - the whole public API of libcrowdbake, one include:
 *
 *     #include <crowdbake/crowdbake.h>      pkg-config --cflags --libs crowdbake
 *                                           CMake: find_package(crowdbake), crowdbake::crowdbake
 *
 * core.h     a model as plain structs, sampling, clip framing, root motion, errors (cb_status)
 * palette.h  palettes: layouts, precisions, the bake of planned clips, decoding
 * runtime.h  what the shipped shaders compute, on the CPU; verification; error-driven rates
 * bake.h     one bake job (a model into .pal/.exr/.ktx2/.bvat.json files): every bake policy, decided once
 * outputs.h  the table of output formats: names, extensions, what each holds, their readers
 * clip_settings.h  each clip's settings resolved once, with where each value came from
 * pool.h     the library's threads, for a program that bakes many models at once
 * stride.h, socket.h   what a game hangs on a clip and a rig: planted feet and footsteps, prop sockets
 * row_travel.h         the per-row travel offset that keeps a gallop's planted feet still (.pal version 5)
 * mesh.h, gltf_mesh_write.h   runtime-ready meshes for a palette (`crowdbake mesh`)
 * gltf.h, pal_write.h, pal_view.h, exr.h, ktx2.h, babylon.h, vat.h, budget.h   files and sizes
 *
 * The tool's plumbing (the JSON writer, atomic files, arenas, name parsers, the sentences that
 * explain a bake) is internal (src/internal/): in libcrowdbake.a for the command, not exported.
 *
 * Catalogs, rosters, the budget report and the preview are the crowdbake command's (cli/),
 * a client of this library like any other program.
 *
 * An engine that only reads palettes needs none of this: crowdbake_pal.h is a dependency-free
 * C99 reader (installed beside this folder).
 *
 * CROWDBAKE_API_VERSION (core.h) is MAJOR * 100 + MINOR: MINOR grows when the API gains
 * something, MAJOR when a change breaks callers (and the shared library's soname with it). */
#ifndef CROWDBAKE_CROWDBAKE_H
#define CROWDBAKE_CROWDBAKE_H

#include "core.h"
#include "palette.h"
#include "runtime.h"
#include "bake.h"
#include "outputs.h"
#include "clip_settings.h"
#include "budget.h"
#include "vat.h"
#include "stride.h"
#include "row_travel.h"
#include "herd_slide.h"
#include "locomotion.h"
#include "plant_feet.h"
#include "socket.h"
#include "mesh.h"
#include "gltf_mesh_write.h"
#include "ktx2.h"
#include "gltf.h"
#include "pal_write.h"
#include "pal_view.h"
#include "exr.h"
#include "babylon.h"
#include "pool.h"

#endif
