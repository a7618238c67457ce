// ktx2_read.cpp - see include/crowdbake/ktx2.h: the KTX2 palettes that ktx2_write.c writes, read
// back. The container (KTX 2.0 specification, section 3) is checked field by field against the
// file's size before anything is read through it; crowdbake's two key/value tables are JSON,
// parsed by simdjson (as the glTF fast path does) and checked against the container and against
// each other, as cbpal_open checks a .pal. Every failure is one line naming the file.
#include "crowdbake/ktx2.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <simdjson.h>
#include <zstd.h>

#include "crowdbake/bake.h"
#include "internal/plumbing.h"

namespace {

using Value = simdjson::dom::element;

enum : uint32_t { VK_FORMAT_R16G16B16A16_SFLOAT = 97, VK_FORMAT_R32G32B32A32_SFLOAT = 109 };
constexpr size_t HEADER_BYTES = 80 + 24; // the header, the index and one level's entry
constexpr uint32_t MAX_BONES = 1u << 16;

uint32_t get32(const unsigned char *d) { return d[0] | d[1] << 8 | d[2] << 16 | (uint32_t)d[3] << 24; }
uint64_t get64(const unsigned char *d) { return get32(d) | (uint64_t)get32(d + 4) << 32; }

// A double rounded to float32 through memory: GCC 12.2 at -O2 was seen storing two adjacent
// `c->fps = (float)fps, c->duration = (float)duration` fields in one vector store, unrounded.
double float32(double d)
{
    volatile float f = (float)d;
    return f;
}

struct Reader {
    const char *path;
    cb_error *err;
    bool failed = false;
    std::string what; // the first thing found wrong

    void fail(const std::string &why)
    {
        if (!failed) what = why;
        failed = true;
    }
};

// The bytes of a file, whole (a palette is at most cb_limits.max_palette_bytes plus its tables).
bool read_file(const char *path, std::vector<unsigned char> &bytes, cb_error *err)
{
    FILE *f = std::fopen(path, "rb");
    if (!f) return cb_fail(err, CB_ERR_IO, "%s: cannot open it", path), false;
    uint64_t limit = cb_default_limits().max_file_bytes;
    unsigned char chunk[1 << 16];
    size_t n;
    while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0 && bytes.size() <= limit) bytes.insert(bytes.end(), chunk, chunk + n);
    bool bad = std::ferror(f);
    std::fclose(f);
    if (bad) return cb_fail(err, CB_ERR_IO, "%s: could not read it", path), false;
    if (bytes.size() > limit)
        return cb_fail(err, CB_ERR_INPUT, "%s: larger than %llu bytes, more than any palette", path, (unsigned long long)limit), false;
    return true;
}

// The key/value data's value for `key` (without its NUL), or false. Each entry: a length, then
// that many bytes (key NUL value NUL), padded to 4 bytes.
bool find_value(const unsigned char *kvd, uint64_t size, const char *key, std::string_view &value, Reader &r)
{
    size_t key_len = std::strlen(key);
    for (uint64_t at = 0; at + 4 <= size;) {
        uint64_t n = get32(kvd + at);
        if (n > size - at - 4) return r.fail("its key/value data has an entry longer than the data"), false;
        const char *entry = (const char *)kvd + at + 4;
        const char *nul = (const char *)std::memchr(entry, 0, (size_t)n);
        if (nul && (size_t)(nul - entry) == key_len && std::memcmp(entry, key, key_len) == 0) {
            size_t rest = (size_t)n - key_len - 1;
            if (rest == 0 || entry[key_len + rest] != 0) return r.fail(std::string("its ") + key + " value does not end in NUL"), false;
            value = std::string_view(nul + 1, rest - 1);
            return true;
        }
        at += (4 + n + 3) / 4 * 4;
    }
    return false;
}

// ---- typed reads of the JSON tables: each names what it wanted ----

bool number(simdjson::dom::object o, const char *key, double &out, Reader &r, bool required = true)
{
    Value v;
    if (o[key].get(v)) {
        if (required) r.fail(std::string("its tables lack '") + key + "'");
        return false;
    }
    if (v.get_double().get(out) || !std::isfinite(out)) return r.fail(std::string("'") + key + "' is not a number"), false;
    return true;
}

uint32_t count(simdjson::dom::object o, const char *key, Reader &r)
{
    Value v;
    uint64_t u = 0;
    if (o[key].get(v) || v.get_uint64().get(u) || u > UINT32_MAX) r.fail(std::string("'") + key + "' is missing or not a count");
    return r.failed ? 0 : (uint32_t)u;
}

bool flag(simdjson::dom::object o, const char *key, Reader &r)
{
    Value v;
    bool b = false;
    if (!o[key].get(v) && v.get_bool().get(b)) r.fail(std::string("'") + key + "' is not true or false");
    return b;
}

std::string_view text(simdjson::dom::object o, const char *key, Reader &r)
{
    Value v;
    std::string_view s;
    if (o[key].get(v) || v.get_string().get(s) || std::memchr(s.data(), 0, s.size()))
        r.fail(std::string("'") + key + "' is missing or not a string");
    return s;
}

// `n` numbers of an optional array into out (zeros when absent and not required).
void floats(simdjson::dom::object o, const char *key, size_t n, float *out, bool required, Reader &r)
{
    Value v;
    simdjson::dom::array a;
    if (o[key].get(v)) {
        if (required) r.fail(std::string("its tables lack '") + key + "'");
        return;
    }
    if (v.get_array().get(a) || a.size() != n) return r.fail(std::string("'") + key + "' does not hold " + std::to_string(n) + " numbers");
    size_t i = 0;
    for (Value e : a) {
        double d;
        if (e.get_double().get(d) || !std::isfinite(d)) return r.fail(std::string("'") + key + "' holds a value that is not a number");
        out[i++] = (float)d;
    }
}

// ---- the tables ----

struct Names {
    std::vector<std::string_view> clips, bones;
};

void read_palette_table(simdjson::dom::object o, cb_ktx2_palette *out, Names &names, Reader &r)
{
    cb_palette *p = &out->palette;
    std::string_view layout = text(o, "layout", r), precision = text(o, "precision", r);
    if (r.failed) return;
    if (!cb_layout_parse(std::string(layout).c_str(), &p->layout)) return r.fail("'layout' is not mat4, affine or qpos");
    cb_precision pr;
    if (!cb_precision_parse(std::string(precision).c_str(), &pr) || pr != p->precision)
        return r.fail("'precision' disagrees with the texture's format");
    p->bone_count = count(o, "bones", r), p->texels_per_bone = count(o, "texels_per_bone", r);
    p->row_texels = count(o, "row_texels", r), p->rows = count(o, "rows", r), p->blocks = count(o, "blocks", r);
    uint32_t rows_per_block = count(o, "rows_per_block", r);
    if (r.failed) return;
    if (p->bone_count == 0 || p->bone_count > MAX_BONES || p->texels_per_bone != cb_layout_texels_per_bone(p->layout) ||
        (uint64_t)p->row_texels != (uint64_t)p->bone_count * p->texels_per_bone || p->blocks == 0 ||
        (uint64_t)p->row_texels * p->blocks != p->width || rows_per_block != p->height ||
        (uint64_t)p->rows > (uint64_t)p->blocks * p->height)
        return r.fail("its palette table (bones, texels per bone, rows, blocks) disagrees with the texture's size");
    p->positions_relative = flag(o, "positions_relative", r);
    p->fitted = flag(o, "fitted_rows", r);
    number(o, "fps", p->fps, r, false);
    Value v;
    std::string_view motion;
    cb_root_motion rm = CB_ROOT_MOTION_KEEP;
    if (!o["root_motion"].get(v) && (v.get_string().get(motion) || !cb_root_motion_parse(std::string(motion).c_str(), &rm)))
        r.fail("'root_motion' is not keep, in-place or loops-in-place");
    out->in_place = rm != CB_ROOT_MOTION_KEEP;
    number(o, "model_height", p->model_height, r), number(o, "max_error", p->max_error, r);
    number(o, "visible_error", p->visible_error, r, false);
    /* float32, as the .pal's header holds them: a palette decodes, plays and verifies the same in either file */
    p->fps = float32(p->fps), p->model_height = float32(p->model_height), p->max_error = float32(p->max_error);
    p->visible_error = float32(p->visible_error);
    double speed = 0;
    number(o, "speed_reference", speed, r, false);
    out->speed_reference = (float)speed;
    std::string_view hash = text(o, "input_hash", r);
    char hex[17] = {0}, *end = nullptr;
    if (!r.failed && hash.size() == 16) std::memcpy(hex, hash.data(), 16), out->input_hash = std::strtoull(hex, &end, 16);
    if (!r.failed && (hash.size() != 16 || end != hex + 16)) r.fail("'input_hash' is not 16 hex digits");
    simdjson::dom::array bones;
    if (r.failed || o["bone_names"].get(v) || v.get_array().get(bones) || bones.size() != p->bone_count)
        return r.fail("'bone_names' does not name every bone");
    for (Value b : bones) {
        std::string_view s;
        if (b.get_string().get(s) || std::memchr(s.data(), 0, s.size())) return r.fail("'bone_names' holds a name that is not a string");
        names.bones.push_back(s);
    }
    p->bind_positions = (float *)std::calloc((size_t)p->bone_count * 3, sizeof(float));
    p->position_offsets = (float *)std::calloc((size_t)p->bone_count * 3, sizeof(float));
    if (!p->bind_positions || !p->position_offsets) return r.fail("out of memory");
    bool needs_bind = p->layout == CB_LAYOUT_QPOS || p->positions_relative;
    floats(o, "bind_positions", (size_t)p->bone_count * 3, p->bind_positions, needs_bind, r);
    floats(o, "position_offsets", (size_t)p->bone_count * 3, p->position_offsets, p->positions_relative, r);
}

void read_clip_table(simdjson::dom::array clips, cb_palette *p, Names &names, Reader &r)
{
    p->clips = (cb_palette_clip *)std::calloc(clips.size() + 1, sizeof *p->clips);
    if (!p->clips) return r.fail("out of memory");
    for (Value e : clips) {
        simdjson::dom::object o;
        if (e.get_object().get(o)) return r.fail("its clip table holds something that is not a clip");
        cb_palette_clip *c = &p->clips[p->clip_count];
        std::string_view name = text(o, "name", r);
        c->first_row = count(o, "first_row", r), c->frames = count(o, "frames", r);
        double fps = 0, duration = 0, start = 0; /* files before "start" was written: clips started at 0 */
        number(o, "fps", fps, r), number(o, "duration", duration, r), number(o, "start", start, r, false);
        c->loops = flag(o, "loops", r), c->fitted = flag(o, "fitted_rows", r), c->step = flag(o, "step_rows", r);
        floats(o, "root_velocity", 3, c->root_velocity, false, r);
        if (r.failed) return;
        c->fps = float32(fps), c->duration = float32(duration), c->start = float32(start); /* as the .pal holds them */
        if (c->frames == 0 || (uint64_t)c->first_row + c->frames > p->rows)
            return r.fail("clip '" + std::string(name) + "' lies outside the palette's " + std::to_string(p->rows) + " rows");
        names.clips.push_back(name);
        ++p->clip_count;
    }
}

// The names, NUL-terminated, in one buffer the palette's clips and bone_names point into.
void keep_names(const Names &names, cb_ktx2_palette *out, Reader &r)
{
    size_t bytes = 1;
    for (auto s : names.clips) bytes += s.size() + 1;
    for (auto s : names.bones) bytes += s.size() + 1;
    out->strings = (char *)std::malloc(bytes);
    out->bone_names = (const char **)std::calloc(names.bones.size() + 1, sizeof(char *));
    if (!out->strings || !out->bone_names) return r.fail("out of memory");
    char *at = out->strings;
    auto keep = [&at](std::string_view s) {
        std::memcpy(at, s.data(), s.size());
        at[s.size()] = 0;
        const char *kept = at;
        at += s.size() + 1;
        return kept;
    };
    for (size_t i = 0; i < names.clips.size(); ++i) out->palette.clips[i].name = keep(names.clips[i]);
    for (size_t i = 0; i < names.bones.size(); ++i) out->bone_names[i] = keep(names.bones[i]);
}

void read_tables(const unsigned char *kvd, uint64_t kvd_bytes, cb_ktx2_palette *out, Reader &r)
{
    std::string_view palette_text, clips_text;
    bool has_palette = find_value(kvd, kvd_bytes, "crowdbake.palette", palette_text, r);
    bool has_clips = !r.failed && find_value(kvd, kvd_bytes, "crowdbake.clips", clips_text, r);
    if (r.failed) return;
    if (!has_palette || !has_clips)
        return r.fail("a KTX2 texture without crowdbake's tables (crowdbake.palette, crowdbake.clips): not a palette "
                      "'crowdbake bake --format ktx2' wrote");
    simdjson::dom::parser palette_parser, clips_parser; // each document lives as long as its parser
    simdjson::dom::object palette;
    simdjson::dom::array clips;
    if (palette_parser.parse(palette_text.data(), palette_text.size()).get_object().get(palette))
        return r.fail("its crowdbake.palette table is not a JSON object");
    if (clips_parser.parse(clips_text.data(), clips_text.size()).get_array().get(clips))
        return r.fail("its crowdbake.clips table is not a JSON array");
    Names names;
    read_palette_table(palette, out, names, r);
    if (!r.failed) read_clip_table(clips, &out->palette, names, r);
    if (!r.failed) keep_names(names, out, r);
}

// The container: returns the level's bytes (the texels), after every check, or null.
const unsigned char *read_container(const std::vector<unsigned char> &file, cb_ktx2_palette *out, uint64_t *stored_bytes,
                                    bool *zstd, Reader &r)
{
    static const unsigned char id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    const unsigned char *d = file.data();
    uint64_t size = file.size();
    if (size < 12 || std::memcmp(d, id, 12) != 0) return r.fail("not a KTX2 file (no KTX 2.0 identifier)"), nullptr;
    if (size < HEADER_BYTES) return r.fail("truncated: " + std::to_string(size) + " bytes, less than a KTX2 header"), nullptr;
    uint32_t format = get32(d + 12), type_size = get32(d + 16), width = get32(d + 20), height = get32(d + 24);
    cb_palette *p = &out->palette;
    if (format == VK_FORMAT_R16G16B16A16_SFLOAT) p->precision = CB_PRECISION_HALF;
    else if (format == VK_FORMAT_R32G32B32A32_SFLOAT) p->precision = CB_PRECISION_FLOAT;
    else return r.fail("vkFormat " + std::to_string(format) + " is not a palette's (RGBA16F or RGBA32F)"), nullptr;
    uint32_t texel = cb_precision_texel_bytes(p->precision);
    uint32_t scheme = get32(d + 44); // 0 none, 2 Zstandard (toktx --zcmp, crowdbake bake --zstd)
    if (type_size != texel / 4 || width == 0 || height == 0 || get32(d + 28) || get32(d + 32) || get32(d + 36) != 1 ||
        get32(d + 40) != 1 || (scheme != 0 && scheme != 2))
        return r.fail("not a palette's texture (one 2D level, no array or cube, no supercompression but zstd)"), nullptr;
    p->width = width, p->height = height;
    uint64_t kvd_at = get32(d + 56), kvd_bytes = get32(d + 60);
    uint64_t level_at = get64(d + 80), level_bytes = get64(d + 88), texels = (uint64_t)width * height * texel;
    if (width > UINT32_MAX / height || (uint64_t)width * height > cb_default_limits().max_palette_bytes / texel ||
        (scheme == 0 && level_bytes != texels) || get64(d + 96) != texels)
        return r.fail("its level's size disagrees with its " + std::to_string(width) + "x" + std::to_string(height) +
                      " texels"), nullptr;
    if (kvd_at > size || kvd_bytes > size - kvd_at || level_at > size || level_bytes > size - level_at)
        return r.fail("truncated: its header places data past its " + std::to_string(size) + " bytes"), nullptr;
    read_tables(d + kvd_at, kvd_bytes, out, r);
    p->texel_bytes = (size_t)texels;
    *stored_bytes = level_bytes;
    *zstd = scheme == 2;
    return r.failed ? nullptr : d + level_at;
}

// The level's texels into the palette: copied, or a Zstandard frame decompressed, which must
// give exactly the texels the header promises.
void take_level(const unsigned char *level, uint64_t stored, bool zstd, cb_palette *p, Reader &r)
{
    if (!(p->texels = std::malloc(p->texel_bytes ? p->texel_bytes : 1))) return r.fail("out of memory");
    if (!zstd) return (void)std::memcpy(p->texels, level, p->texel_bytes);
    size_t n = ZSTD_decompress(p->texels, p->texel_bytes, level, (size_t)stored);
    if (ZSTD_isError(n)) return r.fail(std::string("its zstd level does not decompress: ") + ZSTD_getErrorName(n));
    if (n != p->texel_bytes)
        r.fail("its zstd level holds " + std::to_string(n) + " bytes, not the " + std::to_string(p->texel_bytes) +
               " of its texels");
}

} // namespace

extern "C" cb_status cb_ktx2_read_palette(const char *path, cb_ktx2_palette *out, cb_error *err)
{
    std::memset(out, 0, sizeof *out);
    Reader r{path, err, false, {}};
    try {
        std::vector<unsigned char> file;
        if (!read_file(path, file, err)) return err->status;
        uint64_t stored = 0;
        bool zstd = false;
        const unsigned char *level = read_container(file, out, &stored, &zstd, r);
        if (level) take_level(level, stored, zstd, &out->palette, r);
    } catch (const std::exception &) { // std::bad_alloc: simdjson itself reports through error codes
        r.fail("out of memory");
    }
    if (!r.failed) return CB_OK;
    cb_ktx2_palette_free(out);
    if (r.what == "out of memory") return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", path);
    return cb_fail(err, CB_ERR_INPUT, "%s: %s (bake it again: 'crowdbake bake MODEL --format ktx2')", path, r.what.c_str());
}

extern "C" void cb_ktx2_palette_free(cb_ktx2_palette *p)
{
    cb_palette *v = &p->palette;
    std::free(v->texels), std::free(v->clips), std::free(v->bind_positions), std::free(v->position_offsets);
    std::free(p->bone_names), std::free(p->strings);
    std::memset(p, 0, sizeof *p);
}
