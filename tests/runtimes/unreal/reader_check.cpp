// reader_check.cpp - the Unreal plugin's engine-free part (CrowdbakePalReader, CrowdbakeHerdLogic),
// built with g++ outside Unreal, against the C reader read directly: the texels handed to the
// texture are the file's payload byte for byte, the bind positions and clip table are the C
// reader's, and a herd's custom data gives the C reader's bone matrices (mid-fade included) for
// the states made from the clips. tests/runtimes/test_unreal_reader.c runs it on Fox and Cow in every
// layout x precision. Prints one summary line; exit status 1 with the first difference.
// `reader_check herd FILE.pal ROSTER_LINES TYPE`: a herd of the roster type's states (the lines of
// tests/runtimes/unity/roster_lines.py, Python's reading of roster.json) moving at several speeds
// and changing state: every footstep it raises falls on a contact of its state's clip, and its
// travel offsets are the C reader's cbpal_travel_offset, mixed over a cross-fade.
// `reader_check states ROSTER_LINES`: every state checked against its clip (CheckRosterState: timed rows) and its
// four numbers standing still and moving (tests/runtimes/timed_roster.h reads them).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
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
// spread by the golden ratio, a one-shot from its first row at `start` (docs/roster.md). A timed clip
// (version 7) counts cells at cell_rate instead of rows at fps; cbpal_bone_matrix follows its map.
void Expected(const cbpal_file &pal, uint32_t c, int i, double start, double now, uint32_t bone, float m[16])
{
    cbpal_clip clip;
    cbpal_get_clip(&pal, c, &clip);
    bool timed = (clip.flags & CBPAL_CLIP_TIMED) != 0;
    double fps = timed ? clip.cell_rate : clip.fps, frames = timed ? clip.cells : clip.frames;
    double golden = i * 0.6180339887;
    double phase = (clip.flags & CBPAL_CLIP_LOOPS) ? golden - std::floor(golden) : -start * fps / frames;
    double rows = now * fps + (double)(float)phase * frames;
    cbpal_bone_matrix(&pal, c, rows / fps, bone, m);
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

// The roster type's states, their clips' fps and contacts, from roster_lines.py's lines:
// S type state clip first_row frame_count rate rate_per_speed phase; L type clip first_row frame_count
// fps ...; K type clip foot bone time lift.
// roster_lines.py's lines, each as its words (lines of fewer than three words left out).
static std::vector<std::vector<std::string>> RosterLines(const char *path)
{
    std::ifstream in(path);
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
        std::istringstream f(line);
        std::vector<std::string> row;
        for (std::string word; f >> word;) row.push_back(word);
        if (row.size() >= 3) rows.push_back(row);
    }
    return rows;
}

std::vector<crowdbake::HerdStateInfo> RosterStates(const char *path, const std::string &type)
{
    std::vector<std::vector<std::string>> rows;
    for (auto &row : RosterLines(path))
        if (row[1] == type) rows.push_back(row);
    std::vector<crowdbake::HerdStateInfo> states;
    std::vector<std::string> clip_of;
    std::vector<double> durations;
    for (const auto &r : rows) {
        if (r[0] != "S" || r.size() < 9) continue;
        crowdbake::HerdStateInfo s;
        s.name = r[2], s.first_row = std::stoi(r[4]), s.frame_count = std::stoi(r[5]);
        s.rate = std::stof(r[6]), s.rate_per_speed = std::stof(r[7]), s.golden_ratio_phase = r[8] == "golden_ratio";
        states.push_back(s);
        clip_of.push_back(r[3]);
        durations.push_back(0);
    }
    for (const auto &r : rows)
        for (size_t i = 0; i < states.size(); ++i) {
            if (r[2] != clip_of[i]) continue;
            if (r[0] == "L" && r.size() >= 7) states[i].clip_fps = std::stof(r[5]), durations[i] = std::stod(r[6]);
            if (r[0] == "R" && r.size() >= 4) states[i].clip_fps = (float)(std::stod(r[3]) / durations[i]); // timed: cells / duration
            if (r[0] == "K" && r.size() >= 7) states[i].contacts.push_back({r[3], std::stoi(r[4]), std::stof(r[5]), std::stof(r[6])});
        }
    return states;
}

// The C reader's travel offset for an instance's four numbers at `now` (zero for no clip).
void ExpectedTravel(const cbpal_file &pal, const float inst[4], double now, float out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (uint32_t c = 0; c < pal.header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&pal, c, &clip);
        bool timed = (clip.flags & CBPAL_CLIP_TIMED) != 0;
        if (clip.first_row != (uint32_t)inst[0] || (timed ? clip.cells : clip.frames) != (uint32_t)std::fabs(inst[1])) continue;
        cbpal_travel_offset(&pal, c, (now * std::fabs(inst[2]) + inst[3] * std::fabs((double)inst[1])) / (timed ? clip.cell_rate : clip.fps),
                            out);
    }
}

// Whether a footstep at `time` falls on a contact of the instance's state: its row position then,
// wrapped to the clip for a loop, is a contact's landing or lifting row.
bool OnAContact(const crowdbake::HerdStateInfo &s, const float inst[4], const crowdbake::Footstep &e)
{
    double frames = std::fabs((double)inst[1]), row = e.time * std::fabs((double)inst[2]) + inst[3] * frames;
    for (const crowdbake::HerdContact &k : s.contacts) {
        if (k.bone != e.bone) continue;
        double at = (e.lands ? k.time : k.lift) * s.clip_fps, d = std::fmod(std::fabs(row - at), frames);
        if ((s.frame_count > 0 ? std::fmin(d, frames - d) : std::fabs(row - at)) < 1e-3) return true;
    }
    return false;
}

const crowdbake::HerdStateInfo &StateNamed(const std::vector<crowdbake::HerdStateInfo> &states, const std::string &name)
{
    for (const crowdbake::HerdStateInfo &s : states)
        if (s.name == name) return s;
    return states[0];
}

int Herd(const char *pal_path, const char *lines, const char *type)
{
    std::ifstream in(pal_path, std::ios::binary);
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    cbpal_file pal;
    char err[256];
    if (cbpal_open_memory(bytes.data(), bytes.size(), 0, &pal, err, sizeof err)) return Fail(err);
    std::vector<crowdbake::HerdStateInfo> states = RosterStates(lines, type);
    if (states.empty()) return Fail("the roster lines hold no state of that type");
    const int count = 8;
    crowdbake::HerdLogic herd(states, count, 0.4f);
    std::vector<crowdbake::Footstep> steps;
    for (int i = 0; i < count; ++i) herd.SetState(i, states[(size_t)i % states.size()].name, 0.5, 0.0f, 0.5f + 0.25f * i);
    unsigned footsteps = 0, moving = 0, offsets = 0, faded = 0;
    double worst = 0, last_time[count];
    for (double &t : last_time) t = 0.5;
    for (int step = 1; step <= 40; ++step) {
        double now = 0.5 + step * 0.05;
        steps.clear();
        herd.Advance(now, steps);
        for (const crowdbake::Footstep &e : steps) {
            const float *d = herd.CustomData(e.instance);
            if (!OnAContact(StateNamed(states, herd.StateOf(e.instance)), d, e) || e.time > now + 1e-9 || e.time < last_time[e.instance] - 1e-9)
                return Fail("a footstep at no contact of its clip, or out of order");
            last_time[e.instance] = e.time;
            ++footsteps;
        }
        for (int i = 0; i < count; ++i) {
            float got[3], want[3], from[3];
            herd.TravelOffsetAt(bytes.data(), bytes.size(), i, now, got);
            const float *d = herd.CustomData(i);
            ExpectedTravel(pal, d, now, want);
            float fade = herd.FadeWeight(i, now);
            if (fade < 1) {
                ExpectedTravel(pal, d + 4, now, from);
                for (int k = 0; k < 3; ++k) want[k] = from[k] + (want[k] - from[k]) * fade;
                faded += want[0] != 0 || want[1] != 0 || want[2] != 0;
            }
            if (StateNamed(states, herd.StateOf(i)).rate_per_speed == 0) want[0] = want[1] = want[2] = 0; // a state that does not follow the speed
            for (int k = 0; k < 3; ++k) worst = std::fmax(worst, std::fabs(got[k] - want[k]));
            moving += got[0] != 0 || got[1] != 0 || got[2] != 0;
            ++offsets;
        }
        if (step == 10)
            for (int i = 0; i < count; i += 2) herd.SetState(i, states[(size_t)(i / 2 + 1) % states.size()].name, now, 0.4f);
    }
    cbpal_close(&pal);
    std::printf("herd of %zu states: %u footsteps on their clips' contacts, in order; %u travel offsets (%u moving, %u mid-fade) "
                "worst %.3g from the C reader's\n", states.size(), footsteps, offsets, moving, faded, worst);
    return footsteps > 10 && moving > 0 && worst <= 1e-6 ? 0 : Fail("too few footsteps or moving offsets, or offsets differ");
}

// `reader_check states ROSTER_LINES`: every type's states through CheckRosterState against their clips (L, and R:
// timed_rows) and the type's rows, then HerdLogic's four numbers for instance 1 standing still and at speed 2, a line
// each: D type state cells cell_rate map_rows frame_count rate rate_per_speed still4 moving4 (cells 0: untimed clip).
// A state that does not fit: its error, one line, and exit 1.
int StatesCheck(const char *path)
{
    std::vector<std::vector<std::string>> rows = RosterLines(path);
    std::string out; // printed once every state passed: a refusal is the one line
    for (const auto &t : rows) {
        if (t[0] != "T" || t.size() < 9) continue;
        const std::string &type = t[1];
        std::vector<crowdbake::HerdStateInfo> states = RosterStates(path, type);
        for (crowdbake::HerdStateInfo &s : states) {
            std::string clip_name;
            for (const auto &r : rows)
                if (r[0] == "S" && r[1] == type && r[2] == s.name) clip_name = r[3];
            crowdbake::HerdClipRows clip;
            clip.name = clip_name;
            for (const auto &r : rows) {
                if (r[1] != type || r[2] != clip_name) continue;
                if (r[0] == "L") clip.first_row = std::stoi(r[3]), clip.frame_count = std::stoi(r[4]);
                if (r[0] == "R") clip.cells = std::stoi(r[3]), clip.cell_rate = std::stof(r[4]), clip.map_rows = std::stoi(r[5]);
            }
            std::string error;
            if (!crowdbake::CheckRosterState(s, clip, std::stoi(t[6]), "types." + type + ".states." + s.name + ".instance", error)) {
                std::printf("%s: %s\n", path, error.c_str());
                return 1;
            }
            crowdbake::HerdLogic herd(states, 2, 0.4f);
            float still[4], moving[4];
            herd.SetState(1, s.name, 0.0, 0.0f, 0.0f);
            std::memcpy(still, herd.CustomData(1), sizeof still);
            herd.SetState(1, s.name, 0.0, 0.0f, 2.0f);
            std::memcpy(moving, herd.CustomData(1), sizeof moving);
            char line[1024];
            std::snprintf(line, sizeof line, "D %s %s %d %.9g %d %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", type.c_str(),
                          s.name.c_str(), clip.cells, clip.cell_rate, clip.map_rows, s.frame_count, s.rate, s.rate_per_speed, still[0],
                          still[1], still[2], still[3], moving[0], moving[1], moving[2], moving[3]);
            out += line;
        }
    }
    std::fputs(out.c_str(), stdout);
    return 0;
}

std::vector<uint8_t> ReadBytes(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// `reader_check conformance FILE.pal MESH INSTANCES OUT`: a runtime conformance case (tests/runtimes/conformance.h)
// through the plugin's InstanceBoneMatrix: MESH.positions/.joints/.weights skinned for each line of INSTANCES
// ("time clip4 from4 fade"), cross-faded as the herd fades (matrices mixed), float32 positions into OUT.
int Conformance(const char *pal_path, const std::string &mesh, const char *instances, const char *out_path)
{
    std::vector<uint8_t> pal = ReadBytes(pal_path), pos = ReadBytes(mesh + ".positions"), joints = ReadBytes(mesh + ".joints"),
                         weights = ReadBytes(mesh + ".weights");
    size_t verts = pos.size() / 12;
    std::ifstream in(instances);
    std::ofstream out(out_path, std::ios::binary);
    double time;
    float inst[4], from[4], fade, m[16], f[16];
    std::vector<float> mats;
    uint32_t bones = 0;
    while (in >> time >> inst[0] >> inst[1] >> inst[2] >> inst[3] >> from[0] >> from[1] >> from[2] >> from[3] >> fade) {
        mats.clear();
        for (uint32_t bone = 0;; ++bone) {
            if (!crowdbake::InstanceBoneMatrix(pal.data(), pal.size(), inst, time, bone, m)) break;
            if (fade < 1) {
                if (!crowdbake::InstanceBoneMatrix(pal.data(), pal.size(), from, time, bone, f)) return Fail("the from clip refused");
                for (int k = 0; k < 16; ++k) m[k] = f[k] + (m[k] - f[k]) * fade; // mixing positions = mixing matrices
            }
            mats.insert(mats.end(), m, m + 16);
        }
        if (mats.empty() || (bones && mats.size() / 16 != bones)) return Fail("InstanceBoneMatrix refused an instance");
        bones = (uint32_t)(mats.size() / 16);
        for (size_t v = 0; v < verts; ++v) {
            double p[3] = {0, 0, 0};
            float x[3];
            std::memcpy(x, &pos[v * 12], 12);
            for (int i = 0; i < 4; ++i) {
                float w;
                std::memcpy(&w, &weights[(v * 4 + i) * 4], 4);
                if (w == 0) continue;
                uint32_t j = joints[(v * 4 + i) * 2] | joints[(v * 4 + i) * 2 + 1] << 8;
                const float *a = &mats[(size_t)j * 16];
                for (int c = 0; c < 3; ++c)
                    p[c] += w * ((double)a[c] * x[0] + (double)a[4 + c] * x[1] + (double)a[8 + c] * x[2] + a[12 + c]);
            }
            for (int c = 0; c < 3; ++c) {
                float y = (float)p[c];
                out.write(reinterpret_cast<const char *>(&y), 4);
            }
        }
    }
    return out.good() ? 0 : Fail("cannot write the positions");
}

int main(int argc, char **argv)
{
    if (argc == 6 && std::strcmp(argv[1], "conformance") == 0) return Conformance(argv[2], argv[3], argv[4], argv[5]);
    if (argc == 3 && std::strcmp(argv[1], "skin") == 0) return Skin(argv[2]);
    if (argc == 5 && std::strcmp(argv[1], "herd") == 0) return Herd(argv[2], argv[3], argv[4]);
    if (argc == 3 && std::strcmp(argv[1], "states") == 0) return StatesCheck(argv[2]);
    if (argc != 2) return Fail("usage: reader_check FILE.pal | skin FILE.cbskin | herd FILE.pal ROSTER_LINES TYPE");
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
        if (!pc.local_rows) continue;
        // Local rows: row 2 the parent, row 3 (pos_min, scale_max), row 4 (pos_max, 0), as the shader reads them.
        const float *row2 = &pc.bind_texels[(2 * h.bone_count + j) * 4], *row3 = row2 + h.bone_count * 4, *row4 = row3 + h.bone_count * 4;
        bool same = row2[0] == (float)b.parent && row3[3] == b.scale_max && row4[3] == 0;
        for (int k = 0; k < 3; ++k) same = same && row3[k] == b.pos_min[k] && row4[k] == b.pos_max[k];
        if (!same) return Fail("local rows: the bind texture's parents or bone ranges differ from the file's");
    }
    bool local = (h.flags & CBPAL_FLAG_LOCAL_ROWS) != 0;
    if (pc.local_rows != local || pc.bind_rows != (local ? 5u : 2u) || pc.bind_texels.size() != (size_t)h.bone_count * pc.bind_rows * 4 ||
        local != (pc.defines.back() == "CB_LOCAL_ROWS=1"))
        return Fail("local rows: the bind texture's height or the CB_LOCAL_ROWS define does not match the file's flag bit 5");
    for (uint32_t c = 0; c < h.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&pal, c, &clip);
        const crowdbake::PalClipInfo &x = pc.clips[c];
        if (x.name != clip.name || x.first_row != clip.first_row || x.frames != clip.frames || x.fps != clip.fps ||
            x.loops != ((clip.flags & CBPAL_CLIP_LOOPS) != 0) || x.timed != ((clip.flags & CBPAL_CLIP_TIMED) != 0) ||
            x.cells != clip.cells || x.cell_rate != clip.cell_rate)
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
    double before = 1.7 * std::fabs(d[2]) + d[3] * std::fabs((double)d[1]); // |rate|: a timed clip's is negative
    herd.SetSpeed(1, 2.5f, 1.7);
    d = herd.CustomData(1);
    double after = 1.7 * std::fabs(d[2]) + d[3] * std::fabs((double)d[1]), frames = std::fabs((double)d[1]);
    double drift = std::fmod(std::fabs(before - after), frames);
    drift = std::fmin(drift, frames - drift);
    cbpal_close(&pal);
    unsigned timed = 0;
    for (const crowdbake::PalClipInfo &x : pc.clips) timed += x.timed;
    if (timed && (herd.CustomData(1)[2] < 0) != pc.clips[1 % pc.clips.size()].timed) return Fail("SetSpeed lost a timed clip's sign");
    std::printf("%s: texels, bind positions, %zu clips (%u timed) equal; %u herd matrices (%u mid-fade) worst %.3g; SetSpeed drift %.3g rows; "
                "defines %s %s%s\n", argv[1], pc.clips.size(), timed, matrices, faded, worst, drift, pc.defines[0].c_str(), pc.defines[1].c_str(),
                local ? " CB_LOCAL_ROWS=1" : "");
    return worst <= 1e-6 && drift < 1e-3 && faded > 0 ? 0 : Fail("herd matrices or SetSpeed differ");
}
