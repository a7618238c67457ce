// CrowdbakeHerdLogic.h - what a herd plays, in plain C++ (no Unreal types; tested with g++ in
// tests/runtimes/test_unreal_reader.c): per instance the ten custom-data floats Crowdbake.ush reads (the
// clip's four numbers, the four it cross-fades from, the fade's start and length), states by name,
// speeds that keep feet planted without a pop, scale. The logic of the Unity package's HerdState and
// runtimes/web/crowdbake_three.mjs's CrowdbakeHerd. UCrowdbakeHerdComponent holds one.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "CrowdbakePalReader.h"

namespace crowdbake
{
// A roster state (docs/roster.md): its clip's rows and how fast they play.
struct HerdStateInfo {
    std::string name;
    int32_t first_row = 0, frame_count = 0; // frame_count < 0: a one-shot
    float rate = 0, rate_per_speed = 0;     // rows/s; rows per model unit travelled (0: plays at `rate`)
    bool golden_ratio_phase = true;         // else "zero": a one-shot starts on its first row
};

// A state per clip of a palette without a roster.
std::vector<HerdStateInfo> StatesFromClips(const PalContents &pal);

class HerdLogic
{
public:
    static const int kCustomDataFloats = 10; // Crowdbake.ush's CROWDBAKE_CUSTOM_DATA_FLOATS

    HerdLogic(std::vector<HerdStateInfo> states, int count, float default_fade);

    int Count() const { return count_; }
    // Puts instance i in `state` at herd time `now`, cross-fading over `fade` seconds (< 0: the
    // default); speed < 0 keeps its speed. False (and no change) for an unknown state.
    bool SetState(int i, const std::string &state, double now, float fade = -1, float speed = -1, float phase = -1);
    // World units per second, on the frame it is on (the phase absorbs the change of rate).
    void SetSpeed(int i, float speed, double now);
    void SetScale(int i, float scale, double now);
    // Instance i's ten custom-data floats.
    const float *CustomData(int i) const { return &data_[(size_t)i * kCustomDataFloats]; }
    float FadeWeight(int i, double now) const;
    // The bone's skinning matrix for instance i at `now`, cross-fade included (the file's bytes).
    bool BoneMatrixAt(const uint8_t *pal, size_t size, int i, uint32_t bone, double now, float out[16]) const;
    const std::string &StateOf(int i) const { return state_[(size_t)i]; }
    std::string StateNames() const;

private:
    const HerdStateInfo *Find(const std::string &name) const;
    void InstanceNumbers(const HerdStateInfo &s, double speed, int i, double start, float out[4]) const;

    std::vector<HerdStateInfo> states_;
    int count_;
    float default_fade_;
    std::vector<float> data_, speed_, scale_;
    std::vector<std::string> state_;
};
} // namespace crowdbake
