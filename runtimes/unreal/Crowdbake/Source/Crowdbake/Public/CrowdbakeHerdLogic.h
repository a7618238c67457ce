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
// One of a clip's foot contacts (docs/roster.md `contacts`): the foot lands `time` seconds into the
// clip and lifts at `lift`.
struct HerdContact {
    std::string foot;
    int32_t bone = 0;
    float time = 0, lift = 0;
};

// A roster state (docs/roster.md): its clip's rows and how fast they play.
struct HerdStateInfo {
    std::string name;
    int32_t first_row = 0, frame_count = 0; // frame_count < 0: a one-shot
    float rate = 0, rate_per_speed = 0;     // rows/s (a timed clip: -cells/s); rows per model unit travelled (0: `rate`;
                                            // a timed clip: -cells per unit); != 0: the state follows the speed
    bool golden_ratio_phase = true;         // else "zero": a one-shot starts on its first row
    float clip_fps = 0;                     // the clip's rows per second of clip time (contacts' rows); a timed clip's
                                            // cells / duration (its contacts' cells)
    std::vector<HerdContact> contacts;      // the clip's (none without a roster)
};

// A roster clip's rows (docs/roster.md `clips`) and, for a timed clip (.pal version 7), its `timed_rows`: its map's
// cells, their rate and its map rows (cells 0: the clip plays its rows uniformly).
struct HerdClipRows {
    std::string name;
    int32_t first_row = 0, frame_count = 0;
    int32_t cells = 0, map_rows = 0;
    float cell_rate = 0;
};

// Whether state `s` fits its clip and the type's `type_rows` rows as readRoster (crowdbake_pal.mjs) checks it: a
// timed clip's states count its cells and play at negative rates (rate and rate_per_speed), every other clip's at
// rates >= 0; else false and `error`, one line naming the field under `at` (types.T.states.S.instance).
bool CheckRosterState(const HerdStateInfo &s, const HerdClipRows &clip, int32_t type_rows, const std::string &at, std::string &error);

// A foot landing or lifting that an instance's clock crossed: `time` is the herd clock's moment of it.
struct Footstep {
    int instance = 0;
    std::string foot;
    int32_t bone = 0;
    bool lands = true;
    double time = 0;
};

// The state's contacts crossed as an unwrapped row position (time * rate + phase * frames) moves
// from `from` (exclusive) to `to` (inclusive): {contact index, lands, row crossed}, in the order
// crossed. A loop crosses each contact once a cycle however far it moves; a one-shot clamps to its
// rows and crosses each at most once; nothing is crossed backwards (crowdbake_contacts.mjs).
struct ContactCrossing {
    size_t contact = 0;
    bool lands = true;
    double at = 0;
};
std::vector<ContactCrossing> ContactsCrossed(const HerdStateInfo &s, double from, double to);

// A state per clip of a palette without a roster.
std::vector<HerdStateInfo> StatesFromClips(const PalContents &pal);

class HerdLogic
{
public:
    static const int kCustomDataFloats = 10; // Crowdbake.ush's CROWDBAKE_CUSTOM_DATA_FLOATS
    // The rate a timed instance plays at standstill (crowdbake_pal.mjs TIMED_STILL_RATE): it stays negative to mark
    // the instance timed, and moves it a cell in 3e22 years.
    static constexpr double kTimedStillRate = 1e-30;

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
    // The body's travel offset for instance i at `now` (CBPAL_FLAG_ROW_TRAVEL: glTF model units in the
    // model's frame, to be rotated and scaled as the instance is and added to its place), the two
    // clips' offsets mixed as the cross-fade mixes their poses. Zero at standstill, in a state that
    // does not follow the speed, and for palettes without offsets (crowdbake_three.mjs travelOffsetAt).
    void TravelOffsetAt(const uint8_t *pal, size_t size, int i, double now, float out[3]) const;
    // Appends the footsteps every instance crossed since the last call (or since its state was
    // set), instance by instance, each instance's in the order crossed.
    void Advance(double now, std::vector<Footstep> &out);
    const std::string &StateOf(int i) const { return state_[(size_t)i]; }
    std::string StateNames() const;

private:
    const HerdStateInfo *Find(const std::string &name) const;
    void InstanceNumbers(const HerdStateInfo &s, double speed, int i, double start, float out[4]) const;
    double RowPosition(int i, double now) const;

    std::vector<HerdStateInfo> states_;
    int count_;
    float default_fade_;
    std::vector<float> data_, speed_, scale_;
    std::vector<std::string> state_;
    std::vector<double> position_; // per instance: the row position its footsteps were last raised at
};
} // namespace crowdbake
