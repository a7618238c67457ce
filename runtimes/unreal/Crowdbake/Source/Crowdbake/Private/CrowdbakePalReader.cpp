// CrowdbakePalReader.cpp - see CrowdbakePalReader.h. The C reader is compiled here, once.
#include "CrowdbakePalReader.h"

#include <cmath>
#include <cstring>

#define CROWDBAKE_PAL_IMPLEMENTATION
#include "crowdbake_pal.h"

namespace crowdbake
{
namespace
{
const char *const kLayouts[] = {"CB_LAYOUT_MAT4=1", "CB_LAYOUT_AFFINE=1", "CB_LAYOUT_QPOS=1"};
const char *const kPrecisions[] = {"CB_PRECISION_FLOAT=1", "CB_PRECISION_HALF=1", "CB_PRECISION_U16=1"};

void ReadTables(const cbpal_file &pal, PalContents &out)
{
    const cbpal_header &h = pal.header;
    out.bind_rows = out.local_rows ? 5 : 2;
    out.bind_texels.assign((size_t)h.bone_count * out.bind_rows * 4, 0.0f);
    for (uint32_t j = 0; j < h.bone_count; ++j) {
        cbpal_bone b;
        cbpal_get_bone(&pal, j, &b);
        out.bones.emplace_back(b.name);
        float *row[5];
        for (uint32_t r = 0; r < out.bind_rows; ++r) row[r] = &out.bind_texels[((size_t)r * h.bone_count + j) * 4];
        for (int k = 0; k < 3; ++k) {
            row[0][k] = b.bind_position[k];
            row[1][k] = b.position_offset[k];
            if (!out.local_rows) continue;
            row[3][k] = b.pos_min[k];
            row[4][k] = b.pos_max[k];
        }
        if (!out.local_rows) continue;
        row[2][0] = (float)b.parent; // the shader walks each bone's chain by it
        row[3][3] = b.scale_max;
    }
    for (uint32_t i = 0; i < h.clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(&pal, i, &c);
        PalClipInfo info;
        info.name = c.name;
        info.first_row = c.first_row, info.frames = c.frames, info.fps = c.fps, info.duration = c.duration;
        info.loops = (c.flags & CBPAL_CLIP_LOOPS) != 0;
        info.timed = (c.flags & CBPAL_CLIP_TIMED) != 0, info.cells = c.cells, info.cell_rate = c.cell_rate;
        std::memcpy(info.bounds_min, c.bounds_min, sizeof info.bounds_min);
        std::memcpy(info.bounds_max, c.bounds_max, sizeof info.bounds_max);
        out.clips.push_back(info);
    }
}
} // namespace

bool ReadPal(const uint8_t *data, size_t size, const std::string &name, PalContents &out, std::string &error)
{
    cbpal_file pal;
    char err[256];
    if (cbpal_open_memory(data, size, CBPAL_VERIFY_CHECKSUM, &pal, err, sizeof err) != 0) {
        error = name + ": " + err;
        return false;
    }
    const cbpal_header &h = pal.header;
    out = PalContents();
    out.layout = h.layout, out.precision = h.precision, out.flags = h.flags, out.bone_count = h.bone_count;
    out.row_travel = (h.flags & CBPAL_FLAG_ROW_TRAVEL) != 0;
    out.local_rows = h.range_table_offset != 0;
    out.width = h.width, out.height = h.height, out.row_texels = h.row_texels, out.linear_range = h.linear_range;
    out.model_height = h.model_height, out.speed_reference = h.speed_reference;
    std::memcpy(out.bounds_min, h.bounds_min, sizeof out.bounds_min);
    std::memcpy(out.bounds_max, h.bounds_max, sizeof out.bounds_max);
    // u16 as UNORM16: material textures cannot be RGBA16UI; the shader reads each texel back to its integer.
    const PalPixelFormat formats[] = {PalPixelFormat::Rgba32Float, PalPixelFormat::Rgba16Float, PalPixelFormat::Rgba16Unorm};
    out.format = formats[h.precision];
    const uint8_t *texels = static_cast<const uint8_t *>(pal.texels);
    out.texels.assign(texels, texels + pal.texels_size);
    ReadTables(pal, out);
    out.defines = {kLayouts[h.layout], kPrecisions[h.precision]};
    if (h.flags & CBPAL_FLAG_POSITIONS_RELATIVE) out.defines.emplace_back("CB_POSITIONS_RELATIVE=1");
    if (out.local_rows) out.defines.emplace_back("CB_LOCAL_ROWS=1");
    cbpal_close(&pal);
    return true;
}

static uint32_t U32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

bool ReadSkin(const uint8_t *data, size_t size, const std::string &name, SkinContents &out, std::string &error)
{
    const size_t header = 24;
    if (size < header || std::memcmp(data, "CBSKIN\r\n", 8) != 0) {
        error = name + ": not a crowdbake skin texture (wrong magic); write one with crowdbake mesh --skin-texture";
        return false;
    }
    if (U32(data + 8) != 1) {
        error = name + ": skin texture version " + std::to_string(U32(data + 8)) + " is not 1; update the plugin";
        return false;
    }
    out = SkinContents();
    out.vertex_count = U32(data + 12), out.width = U32(data + 16), out.height = U32(data + 20);
    uint64_t texels = (uint64_t)out.width * out.height;
    if (out.width == 0 || out.height % 2 || (uint64_t)out.vertex_count > texels / 2 ||
        (uint64_t)out.vertex_count + out.width <= texels / 2 || texels * 16 != size - header) {
        error = name + ": inconsistent skin texture (" + std::to_string(out.vertex_count) + " vertices in " + std::to_string(out.width) +
                "x" + std::to_string(out.height) + ", " + std::to_string(size) + " bytes); write it again";
        return false;
    }
    out.texels.resize((size_t)texels * 4);
    for (size_t i = 0; i < out.texels.size(); ++i) {
        uint32_t bits = U32(data + header + 4 * i);
        std::memcpy(&out.texels[i], &bits, 4);
    }
    return true;
}

namespace
{
// The clip an instance's four numbers point at (first row, frame count or a timed clip's cells), and the
// clip time they give at `time`: rows (cells, for inst[2] < 0: a timed clip) played over the clip's rows
// (cells) per second; cbpal_bone_matrix then picks the rows (a timed clip's through its map). False for
// numbers that point at no clip.
bool InstanceClip(const cbpal_file &pal, const float inst[4], double time, uint32_t &clip_index, double &clip_time)
{
    double first = inst[0] < 0 ? -(double)inst[0] - 1 : inst[0]; // < 0: held rows (CBPAL_CLIP_STEP)
    bool timed = inst[2] < 0;
    for (uint32_t c = 0; c < pal.header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&pal, c, &clip);
        if (clip.first_row != (uint32_t)first || ((clip.flags & CBPAL_CLIP_TIMED) != 0) != timed ||
            (timed ? clip.cells : clip.frames) != (uint32_t)std::fabs(inst[1]))
            continue;
        clip_index = c;
        clip_time = (time * std::fabs((double)inst[2]) + inst[3] * std::fabs((double)inst[1])) / (timed ? clip.cell_rate : clip.fps);
        return true;
    }
    return false;
}
} // namespace

bool InstanceBoneMatrix(const uint8_t *data, size_t size, const float inst[4], double time, uint32_t bone, float out[16])
{
    cbpal_file pal;
    char err[256];
    if (cbpal_open_memory(data, size, 0, &pal, err, sizeof err) != 0) return false;
    uint32_t c;
    double t;
    bool found = InstanceClip(pal, inst, time, c, t) && cbpal_bone_matrix(&pal, c, t, bone, out) == 0;
    cbpal_close(&pal);
    return found;
}

bool InstanceTravelOffset(const uint8_t *data, size_t size, const float inst[4], double time, float out[3])
{
    cbpal_file pal;
    char err[256];
    out[0] = out[1] = out[2] = 0;
    if (cbpal_open_memory(data, size, 0, &pal, err, sizeof err) != 0) return false;
    uint32_t c;
    double t;
    bool found = InstanceClip(pal, inst, time, c, t) && cbpal_travel_offset(&pal, c, t, out) == 0;
    cbpal_close(&pal);
    return found;
}
} // namespace crowdbake
