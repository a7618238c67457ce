// CrowdbakePalReader.h - the reading part of the Unreal plugin's .pal import, in plain C++ (no
// Unreal types), so it compiles and is tested outside Unreal (tests/runtimes/test_unreal_reader.c builds it
// with g++): the file is checked and read by the project's C reader, crowdbake_pal.h, and turned
// into what the palette asset keeps: the texels for a texture of the right pixel format, the bind
// positions, the clip table, the header numbers the material needs. The palette asset and the
// factory (CrowdbakePaletteFactory.cpp) call it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace crowdbake
{
// The texture the palette's texels are, byte for byte (Unreal's EPixelFormat of the same layout).
enum class PalPixelFormat { Rgba32Float, Rgba16Float, Rgba16Unorm };

struct PalClipInfo {
    std::string name;
    uint32_t first_row = 0, frames = 0;
    float fps = 0, duration = 0;
    bool loops = false;
    // Version 7, a timed clip (CBPAL_CLIP_TIMED): its rows lie on a grid of `cells` steps, `cell_rate` cells a
    // second, and its instance numbers are (first row, +-cells, -cell_rate x rate, phase); 0 when untimed.
    bool timed = false;
    uint32_t cells = 0;
    float cell_rate = 0;
    float bounds_min[3] = {0, 0, 0}, bounds_max[3] = {0, 0, 0};
};

struct PalContents {
    uint32_t layout = 0, precision = 0, flags = 0, bone_count = 0, width = 0, height = 0, row_texels = 0;
    float linear_range = 0, bounds_min[3] = {0, 0, 0}, bounds_max[3] = {0, 0, 0};
    float model_height = 0, speed_reference = 0;
    bool row_travel = false;          // CBPAL_FLAG_ROW_TRAVEL: moving instances add InstanceTravelOffset
    bool local_rows = false;          // CBPAL_FLAG_LOCAL_ROWS (version 6): the shader's CB_LOCAL_ROWS composes each bone
    PalPixelFormat format = PalPixelFormat::Rgba32Float;
    std::vector<uint8_t> texels;      // width x height texels of 16 or 8 bytes, rows from y = 0
    std::vector<float> bind_texels;   // bone_count x bind_rows RGBA32F: bind positions, then position offsets; local
                                      // rows: row 2 the parents (-1: a root), 3 (pos_min, scale_max), 4 (pos_max, 0)
    uint32_t bind_rows = 2;           // 2, or 5 for local rows
    std::vector<std::string> bones;
    std::vector<PalClipInfo> clips;
    // The material's Additional Defines for this encoding: "CB_LAYOUT_QPOS=1" ...
    std::vector<std::string> defines;
};

// Reads and checks a whole .pal file's bytes (checksum included). False with a one-line error
// naming `name`, the place and the fix (the C reader's message) on a bad file.
bool ReadPal(const uint8_t *data, size_t size, const std::string &name, PalContents &out, std::string &error);

// A skin texture (`crowdbake mesh --skin-texture FILE.cbskin`): vertex v's four joints at
// (v % width, 2 (v / width)), its four weights one row below, RGBA32F.
struct SkinContents {
    uint32_t vertex_count = 0, width = 0, height = 0;
    std::vector<float> texels; // width x height x 4
};

// Reads and checks a .cbskin file's bytes; false with a one-line error naming `name`.
bool ReadSkin(const uint8_t *data, size_t size, const std::string &name, SkinContents &out, std::string &error);

// The bone's skinning matrix (column-major, glTF space: bind space to the posed model) for an
// instance's four numbers (first row, frame count: negative for a one-shot, rate, phase; a timed clip's:
// cells and -cell_rate x rate) at `time`: the clip they point at, through cbpal_bone_matrix, which follows
// a timed clip's map. False for a bone or clip that does not exist.
bool InstanceBoneMatrix(const uint8_t *data, size_t size, const float inst[4], double time, uint32_t bone, float out[16]);

// The body's travel offset (glTF model units, the model's frame) for an instance's four numbers at
// `time`, through cbpal_travel_offset: zero for palettes without per-row travel. False for a clip
// that does not exist.
bool InstanceTravelOffset(const uint8_t *data, size_t size, const float inst[4], double time, float out[3]);
} // namespace crowdbake
