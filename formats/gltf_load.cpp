// gltf_load.cpp - the glTF adapter: parses a plain GLB with simdjson (gltf_fast.cpp) and any
// other file with tinygltf (Draco enabled; the file in gltf_files.cpp, its chunks in gltf_container.cpp),
// decodes EXT_meshopt_compression with libmeshoptimizer, reads every accessor with bounds
// checks and hands the core a cb_model of plain C structs (gltf_convert.cpp).
#include "gltf_parts.h"

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

#include "crowdbake_pal.h"
#include "crowdbake/gltf.h"
#include "internal/plumbing.h"

using namespace cbgltf;

namespace {

// ---- extensions ----

bool extension_supported(const std::string &ext)
{
    static const char *const geometry[] = {"KHR_draco_mesh_compression", "KHR_mesh_quantization",
                                           "EXT_meshopt_compression", "KHR_meshopt_compression"};
    for (const char *g : geometry)
        if (ext == g) return true;
    // Materials, textures and lights do not change joint matrices or skinned positions.
    return ext.rfind("KHR_materials_", 0) == 0 || ext.rfind("KHR_texture_", 0) == 0 ||
           ext.rfind("EXT_texture_", 0) == 0 || ext == "KHR_lights_punctual";
}

bool check_required_extensions(const Context &c, const std::vector<std::string> &required)
{
    for (const std::string &ext : required)
        if (!extension_supported(ext)) {
            cb_fail(c.err, CB_ERR_INPUT,
                    "%s: requires extension %s, which crowdbake does not support (re-export without it)", c.name,
                    ext.c_str());
            return false;
        }
    return true;
}

int meshopt_decode_view(unsigned char *dst, size_t count, size_t stride, const unsigned char *src, size_t src_size,
                        const std::string &mode, const std::string &filter)
{
    int rc;
    if (mode == "ATTRIBUTES")
        rc = meshopt_decodeVertexBuffer(dst, count, stride, src, src_size);
    else if (mode == "TRIANGLES")
        rc = meshopt_decodeIndexBuffer(dst, count, stride, src, src_size);
    else if (mode == "INDICES")
        rc = meshopt_decodeIndexSequence(dst, count, stride, src, src_size);
    else
        return -100;
    if (rc != 0) return rc;
    if (filter == "OCTAHEDRAL")
        meshopt_decodeFilterOct(dst, count, stride);
    else if (filter == "QUATERNION")
        meshopt_decodeFilterQuat(dst, count, stride);
    else if (filter == "EXPONENTIAL")
        meshopt_decodeFilterExp(dst, count, stride);
    else if (!filter.empty() && filter != "NONE")
        return -101;
    return 0;
}

bool decode_meshopt(Context &c, tinygltf::Model *gltf)
{
    for (size_t v = 0; v < gltf->bufferViews.size(); ++v) {
        tinygltf::BufferView &view = gltf->bufferViews[v];
        auto it = view.extensions.find("EXT_meshopt_compression");
        if (it == view.extensions.end()) it = view.extensions.find("KHR_meshopt_compression");
        if (it == view.extensions.end()) continue;
        const tinygltf::Value &e = it->second;
        auto num = [&e](const char *key) -> double {
            return e.Has(key) && e.Get(key).IsNumber() ? e.Get(key).GetNumberAsDouble() : -1.0;
        };
        auto str = [&e](const char *key) -> std::string {
            return e.Has(key) && e.Get(key).IsString() ? e.Get(key).Get<std::string>() : std::string();
        };
        double src_buffer = num("buffer"), src_offset = e.Has("byteOffset") ? num("byteOffset") : 0.0;
        double src_length = num("byteLength"), stride = num("byteStride"), count = num("count");
        bool ok = src_buffer >= 0 && src_buffer < (double)gltf->buffers.size() && src_offset >= 0 && src_length >= 0 &&
                  stride > 0 && stride <= 256 && count >= 0 && count <= (double)c.limits.max_accessor_count;
        const tinygltf::Buffer *src = ok ? &gltf->buffers[(size_t)src_buffer] : nullptr;
        ok = ok && src_offset + src_length <= (double)src->data.size();
        ok = ok && view.buffer >= 0 && view.buffer < (int)gltf->buffers.size();
        tinygltf::Buffer *dst = ok ? &gltf->buffers[(size_t)view.buffer] : nullptr;
        ok = ok && count * stride <= (double)view.byteLength &&
             (double)view.byteOffset + (double)view.byteLength <= (double)dst->data.size();
        if (!ok) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %zu has an EXT_meshopt_compression block with sizes or offsets out of range",
                    c.name, v);
            return false;
        }
        int rc = meshopt_decode_view(dst->data.data() + view.byteOffset, (size_t)count, (size_t)stride,
                                     src->data.data() + (size_t)src_offset, (size_t)src_length, str("mode"), str("filter"));
        if (rc != 0) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %zu: EXT_meshopt_compression data does not decode (%s, error %d)",
                    c.name, v, str("mode").c_str(), rc);
            return false;
        }
    }
    return true;
}

// What the model keeps of the file: the document's buffers, and the file's own bytes when the
// BIN chunk is read where it lies.
struct OwnedBytes {
    std::vector<Bytes> buffers;
    file_bytes file;
};

// Hands the buffers' bytes to the model, so accessors can be read in place.
bool adopt_buffers(Context &c, doc::Document *d, file_bytes *file, const BinInPlace &bin)
{
    std::unique_ptr<OwnedBytes> owned(new OwnedBytes());
    owned->buffers.reserve(d->buffers.size());
    for (Bytes &b : d->buffers) {
        owned->buffers.push_back(std::move(b));
        c.buffers.push_back(Span{owned->buffers.back().data(), owned->buffers.back().size()});
    }
    if (bin.length && !c.buffers.empty()) {
        owned->file = std::move(*file);
        c.buffers[0] = Span{owned->file.data() + bin.at, bin.length};
        if (owned->file.mapped()) {
            c.model->release = release_mapped, c.model->release_ctx = &owned->file;
            const cb_byte_range json = {owned->file.data(), bin.at}; /* parsed and hashed: never read again */
            release_mapped(&owned->file, &json, 1);
        }
    }
    if (!cb_arena_adopt(c.model->arena, owned.get(), [](void *p) { delete static_cast<OwnedBytes *>(p); })) {
        cb_fail(c.err, CB_ERR_INTERNAL, "%s: out of memory", c.name);
        return false;
    }
    owned.release(); // the model's now
    return true;
}

bool record_sources(cb_model *m, cbpal_xxh64_state *hash, const std::vector<std::string> &files)
{
    m->source_hash = cbpal_xxh64_digest(hash);
    m->external_file_count = (uint32_t)files.size();
    m->external_files = static_cast<const char **>(cb_model_alloc(m, files.size() ? files.size() : 1, sizeof(char *)));
    if (!m->external_files) return false;
    for (size_t i = 0; i < files.size(); ++i)
        if (!(m->external_files[i] = cb_model_strdup(m, files[i].c_str()))) return false;
    return true;
}

// `file`, when given, holds `data` and may be taken by the model (the BIN chunk read in place);
// `tail`, when given, may still be reading it.
cb_model *load(const unsigned char *data, size_t size, file_bytes *file, TailRead *tail, const char *name,
               const std::string &base_dir, const cb_limits *limits, cb_error *err)
{
    Context c{};
    c.limits = limits ? *limits : cb_default_limits();
    c.err = err;
    c.name = name;
    doc::Document d;   // what the converter reads: the fast path's, or converted from
    tinygltf::Model gltf; // the tinygltf path's
    bool fast = false;
    cbpal_xxh64_state source_hash;
    cbpal_xxh64_init(&source_hash);
    if (!tail) cbpal_xxh64_update(&source_hash, data, size); /* else the tail's thread hashes the file */
    FsState fs{c.limits.max_file_bytes, &source_hash, {}, false, base_dir};
    BinInPlace bin{0, 0};
    bool parsed = parse_with_tinygltf(data, size, name, base_dir, &fs, &d, &fast, &gltf, file ? &bin : nullptr, tail, err);
    if (tail) {
        tail->wait();
        if (parsed && !tail->ok) cb_fail(err, CB_ERR_IO, "%s: cannot read: short read", name);
        parsed = parsed && tail->ok;
        source_hash = tail->hash; /* no other file was read: the split needs a JSON without uris */
    }
    if (!parsed) return nullptr;
    if (fast ? !check_required_extensions(c, d.extensionsRequired)
             : !check_required_extensions(c, gltf.extensionsRequired) || !decode_meshopt(c, &gltf))
        return nullptr;
    if (!fast) {
        doc_from_tinygltf(&gltf, &d);
        gltf = tinygltf::Model(); // its buffers are d's now; the rest is not read again
    }
    c.doc = &d;
    c.model = cb_model_create(name);
    if (!c.model) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", name);
        return nullptr;
    }
    if (!adopt_buffers(c, &d, file, bin)) {
        cb_model_free(c.model);
        return nullptr;
    }
    if (!convert_nodes(c) || !convert_skins(c) || !check_joints_in_scene(c) || !convert_materials(c) || !convert_meshes(c) ||
        !convert_animations(c) ||
        cb_model_validate(c.model, &c.limits, err) != CB_OK || !record_sources(c.model, &source_hash, fs.files)) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory while loading", name);
        cb_model_free(c.model);
        return nullptr;
    }
    return c.model;
}

cb_model *load_guarded(const unsigned char *data, size_t size, file_bytes *file, TailRead *tail, const char *name,
                       const char *base_dir, const cb_limits *limits, cb_error *err)
{
    try {
        return load(data, size, file, tail, name, base_dir ? base_dir : "", limits, err);
    } catch (const std::bad_alloc &) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory while loading", name);
    } catch (const std::exception &e) {
        cb_fail(err, CB_ERR_INPUT, "%s: not a valid glTF file: %s", name, e.what());
    }
    return nullptr;
}

} // namespace

extern "C" cb_model *cb_gltf_load_memory(const unsigned char *data, size_t size, const char *name, const char *base_dir,
                                         const cb_limits *limits, cb_error *err)
{
    return load_guarded(data, size, nullptr, nullptr, name, base_dir, limits, err);
}

extern "C" cb_model *cb_gltf_load(const char *path, const cb_limits *limits, cb_error *err)
{
    cb_limits l = limits ? *limits : cb_default_limits();
    file_bytes bytes;
    TailRead tail; /* after `bytes`, so it is joined before they are freed */
    std::string why;
    try {
        bool over_limit = false;
        if (!map_model(path, l.max_file_bytes, &bytes, &tail) && !read_file(path, l.max_file_bytes, &bytes, &tail, &why, &over_limit)) {
            cb_fail_setting(err, CB_ERR_IO, over_limit ? CB_SETTING_MAX_FILE_BYTES : CB_SETTING_NONE, "%s: cannot read: %s",
                            path, why.c_str());
            return nullptr;
        }
    } catch (const std::bad_alloc &) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory reading the file", path);
        return nullptr;
    }
    if (bytes.empty()) {
        cb_fail(err, CB_ERR_INPUT, "%s: the file is empty", path);
        return nullptr;
    }
    std::string dir = path;
    size_t slash = dir.find_last_of('/');
    dir = slash == std::string::npos ? "." : slash == 0 ? "/" : dir.substr(0, slash);
    return load_guarded(bytes.data(), bytes.size(), &bytes, tail.head ? &tail : nullptr, path, dir.c_str(), &l, err);
}
