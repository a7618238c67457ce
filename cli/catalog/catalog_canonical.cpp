// catalog_canonical.cpp - an animal's canonical words: every catalog setting that changes its bake,
// in one line, paths as the catalog writes them (relative to its folder), which the roster hashes
// into the type's input key (an unchanged line: an up-to-date type).
#include <cstdio>
#include <string>
#include <vector>

#include "catalog/catalog_canonical.h"
#include "internal/bake_words.h"

/* A resolved path as seen from the catalog's folder: what the catalog says, whatever folder
 * the catalog was named from, so the input hash holds no absolute path (the same bytes in
 * every checkout and build sandbox). A path written absolute stays absolute. */
static std::string from_catalog(const std::string &dir, const std::string &path)
{
    if (!path.empty() && path[0] == '/' && dir[0] != '/') return path;
    auto split = [](const std::string &p) {
        std::vector<std::string> parts;
        for (size_t start = 0; start <= p.size();) {
            size_t end = p.find('/', start);
            if (end == std::string::npos) end = p.size();
            std::string part = p.substr(start, end - start);
            if (!part.empty() && part != ".") parts.push_back(part);
            start = end + 1;
        }
        return parts;
    };
    std::vector<std::string> d = split(dir), f = split(path);
    size_t common = 0;
    while (common < d.size() && common < f.size() && d[common] == f[common]) ++common;
    std::string out;
    for (size_t i = common; i < d.size(); ++i) out += "../";
    for (size_t i = common; i < f.size(); ++i) out += f[i] + (i + 1 < f.size() ? "/" : "");
    return out;
}

static std::string clip_words(const char *what, const cb_catalog_clip &clip)
{
    char buf[128];
    std::snprintf(buf, sizeof buf, " loop=%d fps=%.17g/%d/%.17g", clip.loop, clip.fps, clip.fps_auto, clip.max_error_mm);
    return std::string(what) + clip.source + ">" + clip.name + buf;
}

std::string catalog_canonical_words(const char *dir, const cb_catalog_animal *an)
{
    char buf[256];
    std::string c = std::string("model=") + from_catalog(dir, an->model);
    for (uint32_t i = 0; i < an->lod_count; ++i) c += std::string(" lod=") + from_catalog(dir, an->lods[i]);
    for (uint32_t i = 0; i < an->clip_count; ++i) c += clip_words(" clip=", an->clips[i]);
    // the states' clips are what is baked without a clips list (older records baked every clip)
    if (!an->clips) c += " clips=states";
    for (uint32_t i = 0; i < an->extra_clip_count; ++i) c += clip_words(" extra=", an->extra_clips[i]);
    for (uint32_t i = 0; i < an->state_count; ++i) {
        c += std::string(" state=") + an->states[i].name;
        if (an->states[i].sync != CB_SYNC_AUTO) c += an->states[i].sync == CB_SYNC_SPEED ? "/speed" : "/time";
        for (uint32_t k = 0; k < an->states[i].keyword_count; ++k) c += std::string(",") + an->states[i].keywords[k];
    }
    const cb_bake_settings &b = an->bake;
    std::snprintf(buf, sizeof buf, " fps=%.17g layout=%d/%d precision=%d/%d formats=%u max=%u root=%d speed=%.17g/%d",
                  b.fps, (int)b.layout, b.layout_set, (int)b.precision, b.precision_set, b.formats, b.max_texture_size,
                  (int)b.root_motion, an->speed_reference, an->speed_auto);
    c += buf;
    std::snprintf(buf, sizeof buf, " auto=%d/%.17g/%.17g", b.fps_auto, b.max_error_mm, b.max_fps);
    c += buf;
    if (b.fit_rows) c += " fit_rows";
    if (b.measure_all) c += " measure_all";
    if (b.plant_feet) c += " plant_feet";
    if (b.row_travel_off) c += " row_travel_off";
    /* the catalog's own settings' bone space (a command line's overrides add their words): global keeps its keys */
    if (cb_bake_settings_bone_space(&b, CB_FORMAT_PAL) == CB_BONE_SPACE_LOCAL) c += " bone_space=local";
    if (b.timed_rows != CB_TIMED_ROWS_AUTO) c += std::string(" timed_rows=") + cb_timed_rows_name(b.timed_rows);
    if (b.max_error_given) c += " max_error_given";
    if (b.allow_over_budget) c += " allow_over_budget";
    c += std::string(" default=") + (an->default_state ? an->default_state : "");
    c += std::string(" speed_state=") + (an->speed_state ? an->speed_state : "");
    return c;
}
