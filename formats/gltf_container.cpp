// gltf_container.cpp - the container under the glTF: GLB chunks checked and rebuilt, the JSON
// patched for meshopt fallbacks, tinygltf's parse (its file reads in gltf_files.cpp).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <fcntl.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "gltf_parts.h"

namespace cbgltf {

std::string first_line(const std::string &s)
{
    size_t start = s.find_first_not_of(" \n\r\t");
    if (start == std::string::npos) return "";
    size_t end = s.find('\n', start);
    return s.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

// Little-endian fields of a GLB header or chunk.
uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

bool is_glb(const unsigned char *data, size_t size) { return size >= 4 && std::memcmp(data, "glTF", 4) == 0; }

// memmem costs about 1.7 instructions a byte of a big JSON chunk, and a load asks three times. Here
// blocks of 256 possible starts are screened for the needle's first two bytes side by side, a
// loop without branches that the compiler vectorizes; the few blocks that have such a pair are
// searched byte by byte. The needles asked for ("_compression", "\"uri\"") begin with pairs
// that are rare in glTF JSON.
bool mentions(const void *haystack, size_t size, const char *needle)
{
    size_t len = std::strlen(needle);
    if (len < 2) return len == 0 || std::memchr(haystack, needle[0], size);
    if (size < len) return false;
    const unsigned char *h = static_cast<const unsigned char *>(haystack);
    const unsigned char first = (unsigned char)needle[0], second = (unsigned char)needle[1];
    const size_t starts = size - len + 1; // h[start + 1] is in bounds for each: len >= 2
    size_t at = 0;
    for (; at + 256 <= starts; at += 256) {
        unsigned char pair = 0;
        for (int k = 0; k < 256; ++k) pair |= (h[at + k] == first) & (h[at + k + 1] == second);
        if (!pair) continue;
        for (int k = 0; k < 256; ++k)
            if (h[at + k] == first && std::memcmp(h + at + k, needle, len) == 0) return true;
    }
    for (; at < starts; ++at)
        if (h[at] == first && std::memcmp(h + at, needle, len) == 0) return true;
    return false;
}

// Images are never decoded; the bytes of one given by uri (a data uri or a file) are kept as
// they are for `mesh` (an image in a bufferView is read from the buffer, gltf_materials.cpp).
bool keep_image_bytes(tinygltf::Image *image, const int, std::string *, std::string *, int, int, const unsigned char *bytes,
                      int size, void *)
{
    if (image->bufferView < 0 && bytes && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

// ---- container checks: clearer messages than the parser gives, before it runs ----

bool check_glb(const unsigned char *data, size_t size, const char *name, cb_error *err)
{
    if (size < 20) {
        cb_fail(err, CB_ERR_INPUT, "%s: truncated GLB: %zu bytes, shorter than its 20-byte header", name, size);
        return false;
    }
    uint32_t version = le32(data + 4), length = le32(data + 8);
    if (version != 2) {
        cb_fail(err, CB_ERR_INPUT, "%s: GLB version %u; only glTF 2.0 is supported (re-export as glTF 2.0)", name, version);
        return false;
    }
    if (length > size) {
        cb_fail(err, CB_ERR_INPUT, "%s: truncated GLB: header says %u bytes, file has %zu", name, length, size);
        return false;
    }
    if (length < 20) { /* the JSON chunk is required */
        cb_fail(err, CB_ERR_INPUT, "%s: GLB header says %u bytes, too few for the required JSON chunk", name, length);
        return false;
    }
    size_t offset = 12;
    for (int chunk = 0; offset < length; ++chunk) {
        if (length - offset < 8) {
            cb_fail(err, CB_ERR_INPUT, "%s: GLB chunk %d header at byte %zu runs past the end of the file", name, chunk, offset);
            return false;
        }
        uint32_t chunk_length = le32(data + offset), type = le32(data + offset + 4);
        if (chunk == 0 && type != 0x4E4F534Au) {
            cb_fail(err, CB_ERR_INPUT, "%s: the first GLB chunk is not JSON (type 0x%08x)", name, type);
            return false;
        }
        if (chunk_length > length - offset - 8) {
            cb_fail(err, CB_ERR_INPUT, "%s: GLB chunk %d claims %u bytes, past the end of the file at byte %u", name, chunk,
                    chunk_length, length);
            return false;
        }
        offset += 8 + (size_t)chunk_length;
    }
    return true;
}

// The JSON checks and patches below parse with tinygltf's own parser and flags, so that they
// and tinygltf agree on what the file says.
const rapidjson::Value *member(const rapidjson::Value &v, const char *key)
{
    if (!v.IsObject()) return nullptr;
    auto it = v.FindMember(key);
    return it == v.MemberEnd() ? nullptr : &it->value;
}

size_t array_size(const rapidjson::Value &v, const char *key)
{
    const rapidjson::Value *a = member(v, key);
    return a && a->IsArray() ? a->Size() : 0;
}

// EXT_meshopt_compression puts compressed bytes in one buffer and leaves the "fallback"
// buffer without data, which tinygltf refuses. Give such buffers a URI our file-system
// callback answers with zeros; decode_meshopt() fills them after parsing.
bool patch_meshopt_json(std::string *json)
{
    if (json->find("EXT_meshopt_compression") == std::string::npos) return false;
    rapidjson::Document j;
    j.Parse(json->data(), json->size());
    if (j.HasParseError() || !array_size(j, "buffers")) return false;
    bool patched = false;
    for (rapidjson::Value &b : j.FindMember("buffers")->value.GetArray()) {
        const rapidjson::Value *length = member(b, "byteLength"), *ext = member(b, "extensions");
        if (member(b, "uri") || !length || !length->IsUint64() || !ext || !member(*ext, "EXT_meshopt_compression"))
            continue;
        std::string uri = std::string(kFallbackScheme) + std::to_string(length->GetUint64());
        b.AddMember("uri", rapidjson::Value(uri.c_str(), (rapidjson::SizeType)uri.size(), j.GetAllocator()),
                    j.GetAllocator());
        patched = true;
    }
    if (patched) {
        rapidjson::StringBuffer out;
        rapidjson::Writer<rapidjson::StringBuffer> writer(out);
        j.Accept(writer);
        json->assign(out.GetString(), out.GetSize());
    }
    return patched;
}

// tinygltf's Draco decoder indexes the extension's bufferView, that view's buffer and the
// primitive's accessors without checking them (a fuzzer found it): check them first.
bool check_draco_references(const std::string &json, const char *name, cb_error *err)
{
    if (json.find("KHR_draco_mesh_compression") == std::string::npos) return true;
    rapidjson::Document j;
    j.Parse(json.data(), json.size());
    if (j.HasParseError() || !j.IsObject()) return true; // tinygltf reports the syntax error
    auto index = [](const rapidjson::Value *v, size_t n) { return v && v->IsUint64() && v->GetUint64() < n; };
    size_t views = array_size(j, "bufferViews"), buffers = array_size(j, "buffers"), accessors = array_size(j, "accessors");
    for (size_t m = 0; m < array_size(j, "meshes"); ++m) {
        const rapidjson::Value &mesh = j.FindMember("meshes")->value[(rapidjson::SizeType)m];
        for (size_t p = 0; p < array_size(mesh, "primitives"); ++p) {
            const rapidjson::Value &prim = mesh.FindMember("primitives")->value[(rapidjson::SizeType)p];
            const rapidjson::Value *extensions = member(prim, "extensions");
            const rapidjson::Value *ext = extensions ? member(*extensions, "KHR_draco_mesh_compression") : nullptr;
            if (!ext) continue;
            const rapidjson::Value *view = member(*ext, "bufferView");
            bool ok = index(view, views);
            if (ok) ok = index(member(j.FindMember("bufferViews")->value[(rapidjson::SizeType)view->GetUint64()], "buffer"), buffers);
            if (ok && member(prim, "indices")) ok = index(member(prim, "indices"), accessors);
            const rapidjson::Value *attributes = member(prim, "attributes");
            if (ok && attributes && attributes->IsObject())
                for (auto &a : attributes->GetObject()) ok = ok && index(&a.value, accessors);
            if (!ok) {
                cb_fail(err, CB_ERR_INPUT, "%s: mesh %zu primitive %zu: its KHR_draco_mesh_compression data or accessors "
                        "refer to a bufferView, buffer or accessor that does not exist", name, m, p);
                return false;
            }
        }
    }
    return true;
}

std::vector<unsigned char> rebuild_glb(const std::string &json, const unsigned char *bin, uint32_t bin_length)
{
    std::string padded = json;
    while (padded.size() % 4) padded.push_back(' ');
    std::vector<unsigned char> out;
    auto put32 = [&out](uint32_t v) {
        for (int i = 0; i < 4; ++i) out.push_back((unsigned char)(v >> (8 * i)));
    };
    uint32_t total = 12 + 8 + (uint32_t)padded.size() + (bin ? 8 + bin_length : 0);
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    put32(2);
    put32(total);
    put32((uint32_t)padded.size());
    put32(0x4E4F534Au);
    out.insert(out.end(), padded.begin(), padded.end());
    if (bin) {
        put32(bin_length);
        put32(0x004E4942u);
        out.insert(out.end(), bin, bin + bin_length);
    }
    return out;
}

// ---- a GLB's BIN chunk read in place ----
//
// tinygltf zeroes a buffer the size of the BIN chunk and copies the chunk into it: tens of
// megabytes for a big rig. When the first buffer is the BIN chunk and tinygltf itself never
// reads it (no Draco, no meshopt), it is given a JSON whose first buffer is 1 byte long and
// the accessors read the chunk where it lies in the file's bytes.

// A minimal JSON walker: it only has to find one number; tinygltf parses and checks the
// whole document afterwards.
struct JsonWalk {
    const char *p, *end;
    void space()
    {
        while (p < end && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')) ++p;
    }
    bool eat(char ch)
    {
        space();
        if (p >= end || *p != ch) return false;
        ++p;
        return true;
    }
    bool string(std::string *out) // its raw bytes: escapes are not decoded
    {
        space();
        if (p >= end || *p != '"') return false;
        const char *begin = ++p;
        while (p < end && *p != '"') p += *p == '\\' ? 2 : 1;
        if (p >= end) return false;
        if (out) out->assign(begin, p);
        ++p;
        return true;
    }
    bool skip_value()
    {
        space();
        if (p >= end) return false;
        if (*p == '"') return string(nullptr);
        if (*p != '{' && *p != '[') {
            while (p < end && *p != ',' && *p != '}' && *p != ']') ++p;
            return true;
        }
        int depth = 0;
        do {
            if (*p == '"') {
                if (!string(nullptr)) return false;
                continue;
            }
            depth += *p == '{' || *p == '[' ? 1 : *p == '}' || *p == ']' ? -1 : 0;
            ++p;
        } while (p < end && depth > 0);
        return depth == 0;
    }
};

// Where the digits of buffers[0].byteLength lie in a GLB's JSON, when that buffer has no uri
// (so it is the BIN chunk), and their value.
bool find_bin_byte_length(const std::string &json, size_t *at, size_t *digits, uint64_t *value)
{
    JsonWalk w{json.data(), json.data() + json.size()};
    if (!w.eat('{')) return false;
    do {
        std::string key;
        if (!w.string(&key) || !w.eat(':')) return false;
        if (key != "buffers") continue;
        if (!w.eat('[') || !w.eat('{')) return false;
        bool found = false, uri = false;
        do {
            std::string member;
            if (!w.string(&member) || !w.eat(':')) return false;
            w.space();
            uri = uri || member == "uri";
            if (member != "byteLength") {
                if (!w.skip_value()) return false;
                continue;
            }
            const char *begin = w.p;
            while (w.p < w.end && *w.p >= '0' && *w.p <= '9') ++w.p;
            if (w.p == begin || w.p - begin > 15) return false;
            *at = (size_t)(begin - json.data()), *digits = (size_t)(w.p - begin);
            *value = std::strtoull(begin, nullptr, 10);
            found = true;
        } while (w.eat(','));
        return found && !uri && w.eat('}');
    } while (w.skip_value() && w.eat(','));
    return false;
}

// The GLB to give tinygltf with the BIN chunk left out, and where the chunk lies; false when
// the file needs tinygltf to read it.
bool glb_without_bin(const unsigned char *data, const std::string &json, std::vector<unsigned char> *glb, size_t *bin_at,
                     size_t *bin_length)
{
    size_t at, digits, json_end = 20 + json.size();
    uint64_t length;
    if (json.find("KHR_draco_mesh_compression") != std::string::npos || json_end + 8 > le32(data + 8) ||
        le32(data + json_end + 4) != 0x004E4942u || !find_bin_byte_length(json, &at, &digits, &length) ||
        length > le32(data + json_end))
        return false;
    std::string patched = json;
    patched.replace(at, digits, "1" + std::string(digits - 1, ' '));
    static const unsigned char one_word[4] = {0, 0, 0, 0};
    *glb = rebuild_glb(patched, one_word, sizeof one_word);
    *bin_at = json_end + 8;
    *bin_length = (size_t)length;
    return true;
}

// With `tail` reading the BIN chunk still, only the bytes before it are read until the plain
// parse needs them all.
bool parse_with_tinygltf(const unsigned char *data, size_t size, const char *name, const std::string &base_dir,
                         FsState *fs_state, doc::Document *fast_doc, bool *fast, tinygltf::Model *gltf,
                         BinInPlace *in_place, TailRead *tail, cb_error *err)
{
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keep_image_bytes, nullptr);
    loader.SetFsCallbacks(tinygltf::FsCallbacks{fs_exists, fs_expand, fs_read, fs_write, fs_state});
    std::string tg_err, tg_warn;
    bool ok;
    size_t name_len = std::strlen(name);
    bool glb_name = name_len >= 4 && strcasecmp(name + name_len - 4, ".glb") == 0;
    if (glb_name && !is_glb(data, size)) {
        char magic[5] = {0};
        for (size_t i = 0; i < 4 && i < size; ++i) magic[i] = (data[i] >= 32 && data[i] < 127) ? (char)data[i] : '?';
        cb_fail(err, CB_ERR_INPUT, "%s: not a GLB file: wrong magic '%s' (expected 'glTF')", name, magic);
        return false;
    }
    if (is_glb(data, size)) {
        if (!check_glb(data, size, name, err)) return false;
        size_t settled = tail && tail->head ? tail->head : size; /* past it, the tail's thread may be writing */
        if (parse_fast(data, size, settled, fast_doc, in_place)) return *fast = true; /* a file with Draco is not for it */
        uint32_t json_length = le32(data + 12);
        std::string json((const char *)data + 20, json_length);
        if (!check_draco_references(json, name, err)) return false;
        if (patch_meshopt_json(&json)) {
            size_t bin_at = 20 + (size_t)json_length;
            bool has_bin = bin_at + 8 <= le32(data + 8) && le32(data + bin_at + 4) == 0x004E4942u;
            std::vector<unsigned char> glb =
                rebuild_glb(json, has_bin ? data + bin_at + 8 : nullptr, has_bin ? le32(data + bin_at) : 0);
            ok = loader.LoadBinaryFromMemory(gltf, &tg_err, &tg_warn, glb.data(), (unsigned)glb.size(), base_dir);
        } else {
            std::vector<unsigned char> glb;
            cbpal_xxh64_state hash = *fs_state->source_hash; // as before the first try, if it has to be undone
            size_t files = fs_state->files.size();
            ok = in_place && glb_without_bin(data, json, &glb, &in_place->at, &in_place->length) &&
                 loader.LoadBinaryFromMemory(gltf, &tg_err, &tg_warn, glb.data(), (unsigned)glb.size(), base_dir);
            if (!ok) { // the plain way; its messages are the ones to report
                if (tail) tail->wait();
                if (tail && !tail->ok) {
                    cb_fail(err, CB_ERR_IO, "%s: cannot read: short read", name);
                    return false;
                }
                if (in_place) in_place->length = 0;
                *fs_state->source_hash = hash;
                fs_state->files.resize(files);
                *gltf = tinygltf::Model();
                tg_err.clear();
                ok = loader.LoadBinaryFromMemory(gltf, &tg_err, &tg_warn, data, (unsigned)size, base_dir);
            }
        }
    } else {
        std::string json((const char *)data, size);
        if (!check_draco_references(json, name, err)) return false;
        patch_meshopt_json(&json);
        ok = loader.LoadASCIIFromString(gltf, &tg_err, &tg_warn, json.c_str(), (unsigned)json.size(), base_dir);
    }
    if (!ok) {
        std::string why = first_line(tg_err);
        cb_fail_setting(err, CB_ERR_INPUT, fs_state->over_limit ? CB_SETTING_MAX_FILE_BYTES : CB_SETTING_NONE,
                        "%s: not a valid glTF 2.0 file: %s", name, why.empty() ? "parse failed" : why.c_str());
    }
    return ok;
}

} // namespace cbgltf
