// CrowdbakeHerdLogic.cpp - see CrowdbakeHerdLogic.h.
#include "CrowdbakeHerdLogic.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace crowdbake
{
std::vector<HerdStateInfo> StatesFromClips(const PalContents &pal)
{
    std::vector<HerdStateInfo> states;
    for (const PalClipInfo &c : pal.clips) {
        HerdStateInfo s;
        s.name = c.name;
        s.first_row = (int32_t)c.first_row;
        int32_t count = (int32_t)(c.timed ? c.cells : c.frames); // a timed clip: its cells at -cell_rate (cbpal_clip)
        s.frame_count = c.loops ? count : -count;
        s.rate = c.timed ? -c.cell_rate : c.fps;
        s.golden_ratio_phase = c.loops;
        states.push_back(s);
    }
    return states;
}

bool CheckRosterState(const HerdStateInfo &s, const HerdClipRows &clip, int32_t type_rows, const std::string &at, std::string &error)
{
    const bool timed = clip.cells > 0;
    if ((s.rate < 0) != timed || s.rate_per_speed * s.rate < 0) {
        error = at + ".rate: " + (timed ? "clip \"" + clip.name + "\" has timed rows: rate and rate_per_speed must be negative"
                                        : std::string("expected a number >= 0, and rate_per_speed too"));
        return false;
    }
    if (s.frame_count == 0 || (timed && std::abs((int64_t)s.frame_count) != clip.cells)) {
        error = at + ".frame_count: " + (timed ? "clip \"" + clip.name + "\" has " + std::to_string(clip.cells) + " cells, got " +
                                                     std::to_string(s.frame_count)
                                               : std::string("expected a non-zero integer"));
        return false;
    }
    int64_t first = s.first_row < 0 ? -(int64_t)s.first_row - 1 : s.first_row; // held rows: -first_row - 1
    int64_t rows = timed ? clip.frame_count : std::abs((int64_t)s.frame_count); // a timed state counts cells, not rows
    if (first + rows > type_rows || (timed && clip.map_rows > first)) {
        error = at + ": rows " + std::to_string(first) + ".." + std::to_string(first + rows) + " outside the type's " +
                std::to_string(type_rows) + " rows";
        return false;
    }
    return true;
}

std::vector<ContactCrossing> ContactsCrossed(const HerdStateInfo &s, double from, double to)
{
    std::vector<ContactCrossing> out;
    if (!(to > from) || s.contacts.empty()) return out;
    double frames = std::fabs((double)s.frame_count), end = s.rate < 0 ? frames : frames - 1; // a timed state: cells
    if (s.frame_count < 0) { // one-shot: clamped to its rows
        from = std::min(std::max(from, 0.0), end);
        to = std::min(std::max(to, 0.0), end);
    }
    for (size_t c = 0; c < s.contacts.size(); ++c)
        for (bool lands : {true, false}) {
            double row = (double)(lands ? s.contacts[c].time : s.contacts[c].lift) * s.clip_fps;
            if (s.frame_count < 0) {
                if (from < row && row <= to) out.push_back({c, lands, row});
                continue;
            }
            for (double k = std::floor((from - row) / frames) + 1; row + k * frames <= to; ++k) out.push_back({c, lands, row + k * frames});
        }
    std::stable_sort(out.begin(), out.end(), [](const ContactCrossing &a, const ContactCrossing &b) {
        return a.at != b.at ? a.at < b.at : a.contact != b.contact ? a.contact < b.contact : a.lands && !b.lands;
    });
    return out;
}

HerdLogic::HerdLogic(std::vector<HerdStateInfo> states, int count, float default_fade)
    : states_(std::move(states)), count_(std::max(count, 0)), default_fade_(default_fade),
      data_((size_t)count_ * kCustomDataFloats, 0.0f), speed_((size_t)count_, 0.0f), scale_((size_t)count_, 1.0f),
      state_((size_t)count_), position_((size_t)count_, std::nan(""))
{
    for (int i = 0; i < count_ && !states_.empty(); ++i) SetState(i, states_[0].name, 0.0, 0.0f);
}

const HerdStateInfo *HerdLogic::Find(const std::string &name) const
{
    for (const HerdStateInfo &s : states_)
        if (s.name == name) return &s;
    return nullptr;
}

std::string HerdLogic::StateNames() const
{
    std::string names;
    for (const HerdStateInfo &s : states_) names += (names.empty() ? "" : ", ") + s.name;
    return names;
}

// docs/roster.md's four numbers: moving at `speed` model units/s, index i, a one-shot started at `start`.
// A state follows the speed when rate_per_speed != 0 (a timed one's is negative). A timed state (rate < 0,
// .pal version 7) keeps the sign: its rate is -cells a second, and standing still -kTimedStillRate, never -0,
// which would read as an untimed clip's (its cells taken for rows).
void HerdLogic::InstanceNumbers(const HerdStateInfo &s, double speed, int i, double start, float out[4]) const
{
    double rate = s.rate_per_speed != 0 ? std::fabs(s.rate_per_speed) * speed : std::fabs(s.rate);
    double frames = std::fabs((double)s.frame_count), golden = i * 0.6180339887;
    out[0] = (float)s.first_row;
    out[1] = (float)s.frame_count;
    out[2] = (float)(s.rate < 0 ? -std::max(rate, kTimedStillRate) : rate);
    out[3] = (float)(s.golden_ratio_phase ? golden - std::floor(golden) : -start * rate / frames);
}

bool HerdLogic::SetState(int i, const std::string &state, double now, float fade, float speed, float phase)
{
    const HerdStateInfo *s = Find(state);
    if (!s || i < 0 || i >= count_) return false;
    if (speed < 0) speed = speed_[(size_t)i];
    if (fade < 0) fade = default_fade_;
    float *d = &data_[(size_t)i * kCustomDataFloats];
    float current[4];
    std::memcpy(current, d, sizeof current);
    InstanceNumbers(*s, speed / scale_[(size_t)i], i, now, d); // world speed / scale: the model's own speed
    if (phase >= 0) d[3] = phase;
    std::memcpy(d + 4, fade > 0 && current[1] != 0 ? current : d, sizeof current);
    d[8] = (float)now;
    d[9] = fade;
    state_[(size_t)i] = state;
    speed_[(size_t)i] = speed;
    position_[(size_t)i] = RowPosition(i, now); // what the new numbers have passed is behind the instance
    return true;
}

// Instance i's unwrapped row position at `now` (crowdbake_contacts.mjs rowPosition).
double HerdLogic::RowPosition(int i, double now) const
{
    const float *d = CustomData(i);
    return now * std::fabs((double)d[2]) + d[3] * std::fabs((double)d[1]);
}

void HerdLogic::Advance(double now, std::vector<Footstep> &out)
{
    for (int i = 0; i < count_; ++i) {
        double to = RowPosition(i, now), from = position_[(size_t)i], rate = std::fabs((double)CustomData(i)[2]); // timed: z < 0
        position_[(size_t)i] = to;
        const HerdStateInfo *s = Find(state_[(size_t)i]);
        if (!s || std::isnan(from) || !(rate > 0)) continue;
        for (const ContactCrossing &c : ContactsCrossed(*s, from, to)) {
            const HerdContact &k = s->contacts[c.contact];
            out.push_back({i, k.foot, k.bone, c.lands, now - (to - c.at) / rate});
        }
    }
}

void HerdLogic::TravelOffsetAt(const uint8_t *pal, size_t size, int i, double now, float out[3]) const
{
    out[0] = out[1] = out[2] = 0;
    const HerdStateInfo *s = Find(state_[(size_t)i]);
    if (!s || s->rate_per_speed == 0 || !(speed_[(size_t)i] > 0)) return;
    const float *d = CustomData(i);
    InstanceTravelOffset(pal, size, d, now, out);
    float fade = FadeWeight(i, now), from[3];
    if (fade >= 1 || !InstanceTravelOffset(pal, size, d + 4, now, from)) return;
    for (int k = 0; k < 3; ++k) out[k] = from[k] + (out[k] - from[k]) * fade;
}

void HerdLogic::SetSpeed(int i, float speed, double now)
{
    const float *d = CustomData(i);
    double frames = std::fabs((double)d[1]), rows = now * std::fabs((double)d[2]) + d[3] * frames;
    float next[4];
    InstanceNumbers(*Find(state_[(size_t)i]), speed / scale_[(size_t)i], i, now, next);
    double p = (rows - now * std::fabs((double)next[2])) / frames;
    SetState(i, state_[(size_t)i], now, 0.0f, speed, (float)(p - std::floor(p)));
}

void HerdLogic::SetScale(int i, float scale, double now)
{
    float was = scale_[(size_t)i];
    scale_[(size_t)i] = scale;
    if (was != scale && Find(state_[(size_t)i])->rate_per_speed != 0) SetSpeed(i, speed_[(size_t)i], now);
}

float HerdLogic::FadeWeight(int i, double now) const
{
    const float *d = CustomData(i);
    return d[9] > 0 ? (float)std::min(std::max((now - d[8]) / d[9], 0.0), 1.0) : 1.0f;
}

bool HerdLogic::BoneMatrixAt(const uint8_t *pal, size_t size, int i, uint32_t bone, double now, float out[16]) const
{
    const float *d = CustomData(i);
    if (!InstanceBoneMatrix(pal, size, d, now, bone, out)) return false;
    float fade = FadeWeight(i, now), from[16];
    if (fade >= 1) return true;
    if (!InstanceBoneMatrix(pal, size, d + 4, now, bone, from)) return false;
    for (int k = 0; k < 16; ++k) out[k] = from[k] + (out[k] - from[k]) * fade; // mixing positions = mixing matrices
    return true;
}
} // namespace crowdbake
