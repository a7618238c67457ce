// reader_check.cpp - the Unreal plugin's engine-free part (CrowdbakePalReader, CrowdbakeHerdLogic),
// built with g++ outside Unreal, against the C reader read directly: the texels handed to the
// texture are the file's payload byte for byte, the bind positions and clip table are the C
// reader's, and a herd's custom data gives the C reader's bone matrices (mid-fade included) for
// the states made from the clips. tests/runtimes/test_unreal_reader.c runs it on Fox and Cow in every
// layout x precision. Prints one summary line; exit status 1 with the first difference.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

#include "CrowdbakeHerdLogic.h"
#include "CrowdbakePalReader.h"
#include "crowdbake_pal.h"

namespace
{
int Fail(const char *what)
{
    std::fprintf(stderr, "reader_check: %s\n", what);
    return 1;
}

// The C reader's matrix for the state of clip `c` entered by instance i at `start`, at `now`: a loop
// spread by the golden ratio, a one-shot from its first row at `start` (docs/roster.md).
void Expected(const cbpal_file &pal, uint32_t c, int i, double start, double now, uint32_t bone, float m[16])
{
    cbpal_clip clip;
    cbpal_get_clip(&pal, c, &clip);
    double golden = i * 0.6180339887;
    double phase = (clip.flags & CBPAL_CLIP_LOOPS) ? golden - std::floor(golden) : -start * clip.fps / clip.frames;
    double rows = now * (double)clip.fps + (double)(float)phase * clip.frames;
    cbpal_bone_matrix(&pal, c, rows / clip.fps, bone, m);
}
} // namespace

// `reader_check skin FILE.cbskin`: every vertex's joints and weights as ReadSkin gives them, one line each.
int Skin(const char *path)
{
    std::ifstream in(path, std::ios::binary);
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    crowdbake::SkinContents skin;
    std::string error;
    if (!crowdbake::ReadSkin(bytes.data(), bytes.size(), path, skin, error)) return Fail(error.c_str());
    for (uint32_t v = 0; v < skin.vertex_count; ++v) {
        size_t j = ((size_t)(v / skin.width) * 2 * skin.width + v % skin.width) * 4, w = j + (size_t)skin.width * 4;
        std::printf("%u %g %g %g %g %.9g %.9g %.9g %.9g\n", v, skin.texels[j], skin.texels[j + 1], skin.texels[j + 2], skin.texels[j + 3],
                    skin.texels[w], skin.texels[w + 1], skin.texels[w + 2], skin.texels[w + 3]);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && std::strcmp(argv[1], "skin") == 0) return Skin(argv[2]);
    if (argc != 2) return Fail("usage: reader_check FILE.pal | skin FILE.cbskin");
    std::ifstream in(argv[1], std::ios::binary);
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    crowdbake::PalContents pc;
    std::string error;
    if (!crowdbake::ReadPal(bytes.data(), bytes.size(), argv[1], pc, error)) return Fail(error.c_str());
    cbpal_file pal;
    char err[256];
    if (cbpal_open_memory(bytes.data(), bytes.size(), 0, &pal, err, sizeof err)) return Fail(err);
    const cbpal_header &h = pal.header;
    if (pc.texels.size() != pal.texels_size || std::memcmp(pc.texels.data(), pal.texels, pal.texels_size) != 0)
        return Fail("the texture's texels are not the file's payload");
    if (pc.width != h.width || pc.height != h.height || pc.layout != h.layout || pc.precision != h.precision ||
        pc.bone_count != h.bone_count || pc.row_texels != h.row_texels || pc.linear_range != h.linear_range ||
        (int)pc.format != (int)h.precision || pc.clips.size() != h.clip_count)
        return Fail("header numbers differ");
    for (uint32_t j = 0; j < h.bone_count; ++j) {
        cbpal_bone b;
        cbpal_get_bone(&pal, j, &b);
        for (int k = 0; k < 3; ++k)
            if (pc.bind_texels[j * 4 + k] != b.bind_position[k] || pc.bind_texels[(h.bone_count + j) * 4 + k] != b.position_offset[k])
                return Fail("bind positions differ");
    }
    for (uint32_t c = 0; c < h.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&pal, c, &clip);
        const crowdbake::PalClipInfo &x = pc.clips[c];
        if (x.name != clip.name || x.first_row != clip.first_row || x.frames != clip.frames || x.fps != clip.fps ||
            x.loops != ((clip.flags & CBPAL_CLIP_LOOPS) != 0))
            return Fail("clip table differs");
    }
    // A herd: instance i in the state of clip i % clips; half of them cross-fade into the next clip.
    const int count = 6;
    crowdbake::HerdLogic herd(crowdbake::StatesFromClips(pc), count, 0.5f);
    double worst = 0;
    unsigned matrices = 0, faded = 0;
    for (int i = 0; i < count; ++i) herd.SetState(i, pc.clips[i % h.clip_count].name, 0.0, 0.0f);
    for (int i = 0; i < count; i += 2) herd.SetState(i, pc.clips[(i + 1) % h.clip_count].name, 1.0, 0.5f);
    for (double now : {1.2, 1.7}) // mid-fade, then after it
        for (int i = 0; i < count; ++i)
            for (uint32_t bone = 0; bone < h.bone_count; bone += 5) {
                float got[16], want[16], from[16];
                if (!herd.BoneMatrixAt(bytes.data(), bytes.size(), i, bone, now, got)) return Fail("BoneMatrixAt refused");
                uint32_t c = (uint32_t)((i % 2 == 0 ? i + 1 : i) % h.clip_count);
                Expected(pal, c, i, i % 2 == 0 ? 1.0 : 0.0, now, bone, want);
                float fade = i % 2 == 0 ? (float)std::fmin((now - 1.0) / 0.5, 1.0) : 1.0f;
                if (fade < 1) {
                    Expected(pal, (uint32_t)(i % h.clip_count), i, 0.0, now, bone, from);
                    for (int k = 0; k < 16; ++k) want[k] = from[k] + (want[k] - from[k]) * fade;
                    ++faded;
                }
                for (int k = 0; k < 16; ++k) worst = std::fmax(worst, std::fabs(got[k] - want[k]) / std::fmax(1.0, std::fabs(want[k])));
                ++matrices;
            }
    // SetSpeed keeps the frame: the row position before and after are the same.
    const float *d = herd.CustomData(1);
    double before = 1.7 * d[2] + d[3] * std::fabs((double)d[1]);
    herd.SetSpeed(1, 2.5f, 1.7);
    d = herd.CustomData(1);
    double after = 1.7 * d[2] + d[3] * std::fabs((double)d[1]), frames = std::fabs((double)d[1]);
    double drift = std::fmod(std::fabs(before - after), frames);
    drift = std::fmin(drift, frames - drift);
    cbpal_close(&pal);
    std::printf("%s: texels, bind positions, %zu clips equal; %u herd matrices (%u mid-fade) worst %.3g; SetSpeed drift %.3g rows; "
                "defines %s %s\n", argv[1], pc.clips.size(), matrices, faded, worst, drift, pc.defines[0].c_str(), pc.defines[1].c_str());
    return worst <= 1e-6 && drift < 1e-3 && faded > 0 ? 0 : Fail("herd matrices or SetSpeed differ");
}
