// gltf_parts.h - what the glTF adapter's files share (private to libcrowdbake):
// gltf_files.cpp reads the file (and the external files it names), gltf_container.cpp hands its
// JSON to gltf_fast.cpp (a plain GLB) or to tinygltf (the rest), gltf_convert.cpp reads the
// accessors into the core's structs, gltf_load.cpp runs the load.
#ifndef CB_GLTF_PARTS_H
#define CB_GLTF_PARTS_H

#include "tinygltf_config.h"

#include <cstdlib>
#include <new>
#include <string>
#include <thread>
#include <utility>
#include <vector>
#include <sys/mman.h>

#include "crowdbake_pal.h"
#include "crowdbake/gltf.h"
#include "internal/plumbing.h"

namespace cbgltf {

inline constexpr const char kFallbackScheme[] = "crowdbake-meshopt-fallback-";

using Bytes = std::vector<unsigned char>;

// ---- the parsed document: what a bake reads of a glTF, and nothing else ----
//
// Plain structs, filled by the fast path from simdjson's DOM (gltf_fast.cpp) or converted from
// tinygltf's Model on the other path (doc_from_tinygltf), so the converter has one input. A big
// rig has tens of thousands of accessors, views, channels and samplers: tinygltf's structs for
// them carry strings, maps and extension trees of a few hundred bytes each, built and freed
// for nothing. Members keep tinygltf's names, types and defaults.
namespace doc {

struct BufferView {
    int buffer = -1;
    size_t byteOffset = 0, byteLength = 0, byteStride = 0;
};

struct Accessor {
    int bufferView = -1;
    size_t byteOffset = 0;
    bool normalized = false;
    int componentType = -1;
    size_t count = 0;
    int type = -1;
    struct {
        int count = 0;
        bool isSparse = false;
        struct {
            int byteOffset = 0, bufferView = -1, componentType = -1;
        } indices;
        struct {
            int bufferView = -1, byteOffset = 0;
        } values;
    } sparse;
};

struct Primitive {
    std::vector<std::pair<std::string, int>> attributes; // name, accessor; each name once
    int indices = -1;
    int material = -1;
    const int *attribute(const char *name) const
    {
        for (const auto &a : attributes)
            if (a.first == name) return &a.second;
        return nullptr;
    }
};

struct Mesh {
    std::vector<Primitive> primitives;
};

struct Node {
    std::string name;
    int skin = -1, mesh = -1;
    std::vector<int> children;
    std::vector<double> matrix, translation, rotation, scale; // as given: sizes are checked later
};

struct Skin {
    std::string name;
    std::vector<int> joints;
    int skeleton = -1, inverseBindMatrices = -1;
};

struct AnimationChannel {
    int sampler = -1, target_node = -1;
    std::string target_path; // short: no allocation
};

struct AnimationSampler {
    int input = -1, output = -1;
    std::string interpolation; // short: no allocation
};

struct Animation {
    std::string name;
    std::vector<AnimationChannel> channels;
    std::vector<AnimationSampler> samplers;
};

struct Scene {
    std::vector<int> nodes;
};

// What a primitive looks like (kept for `crowdbake mesh`, see gltf_materials.cpp).
struct Material {
    std::string name;
    double base_color[4] = {1, 1, 1, 1};
    double metallic = 1, roughness = 1;
    int base_color_texture = -1, base_color_texcoord = 0;
    std::string alpha_mode = "OPAQUE";
    double alpha_cutoff = 0.5;
    bool double_sided = false;
};

struct Texture {
    int source = -1, sampler = -1;
};

struct Image {
    int bufferView = -1;
    std::string mimeType;
    Bytes bytes;     // an image given by a data uri: its bytes, as tinygltf decoded them
    std::string uri; // an image in a file: its uri (tinygltf reads no external image)
};

struct Sampler {
    int magFilter = -1, minFilter = -1, wrapS = 10497, wrapT = 10497;
};

struct Document {
    std::vector<std::string> extensionsRequired;
    std::vector<Bytes> buffers; // their bytes; an empty one where the BIN chunk is read in place
    std::vector<BufferView> bufferViews;
    std::vector<Accessor> accessors;
    std::vector<Mesh> meshes;
    std::vector<Node> nodes;
    std::vector<Scene> scenes;
    int defaultScene = -1;
    std::vector<Animation> animations;
    std::vector<Skin> skins;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<Image> images;
    std::vector<Sampler> samplers;
};

} // namespace doc

struct Span {
    unsigned char *data;
    size_t size;
};

struct Context {
    cb_model *model;
    const doc::Document *doc; // what the file holds, from either parse
    std::vector<Span> buffers;   // the bytes of each buffer, which the model owns
    cb_limits limits;
    cb_error *err;
    const char *name;
};

// The model file's bytes: read into memory that resize() leaves uninitialized (the file is
// read over it at once, and zeroing tens of megabytes first costs as much as the read), on huge
// pages where the OS has them (cb_alloc_large); or a mapping of the file (map_model).
class file_bytes {
  public:
    file_bytes() = default;
    file_bytes(const file_bytes &) = delete;
    file_bytes &operator=(const file_bytes &) = delete;
    file_bytes(file_bytes &&o) noexcept { take(o); }
    file_bytes &operator=(file_bytes &&o) noexcept
    {
        if (this != &o) release(), take(o);
        return *this;
    }
    ~file_bytes() { release(); }
    void resize(size_t n)
    {
        release();
        if (n && !(bytes_ = static_cast<unsigned char *>(cb_alloc_large(n)))) throw std::bad_alloc();
        size_ = n;
    }
    void adopt_mapping(void *p, size_t n)
    {
        release();
        bytes_ = static_cast<unsigned char *>(p), size_ = n, mapped_ = true;
    }
    unsigned char *data() { return bytes_; }
    const unsigned char *bytes() const { return bytes_; }
    size_t size() const { return size_; }
    bool mapped() const { return mapped_; } // a read-only mapping of the file (map_model)
    bool empty() const { return size_ == 0; }

  private:
    void release()
    {
        if (mapped_) munmap(bytes_, size_);
        else std::free(bytes_);
        bytes_ = nullptr, size_ = 0, mapped_ = false;
    }
    void take(file_bytes &o)
    {
        bytes_ = o.bytes_, size_ = o.size_, mapped_ = o.mapped_;
        o.bytes_ = nullptr, o.size_ = 0, o.mapped_ = false;
    }
    unsigned char *bytes_ = nullptr;
    size_t size_ = 0;
    bool mapped_ = false;
};

// ---- a big GLB read on two threads ----
//
// A GLB whose BIN chunk tinygltf never reads (no Draco, no meshopt, no external files) is read
// in two parts: its header, JSON chunk and BIN chunk header at once, and the BIN chunk on a
// second thread, which also hashes the file, while tinygltf parses the JSON. For a large rig
// the read (and the page faults of its buffer) then costs no wall time.
struct TailRead {
    std::thread thread;
    size_t head = 0;           // bytes read before the thread started; 0: no thread
    bool ok = false;           // the thread read every byte
    cbpal_xxh64_state hash{};  // of the whole file, once ok
    void wait()
    {
        if (thread.joinable()) thread.join();
    }
    ~TailRead() { wait(); }
};

struct FsState {
    uint64_t max_bytes;
    cbpal_xxh64_state *source_hash; // every external file read goes into the model's source hash
    std::vector<std::string> files;  // and into its list of external files, for depfiles
    bool over_limit;                 // a file was refused for max_bytes
    std::string folder;              // the model's folder: external files are read only inside it ("": none)
};

struct BinInPlace {
    size_t at, length; // length 0: tinygltf read the BIN chunk itself
};

// gltf_container.cpp
uint32_t le32(const unsigned char *p); // a little-endian field of a GLB header or chunk
// Whether the C string `needle` occurs in the `size` bytes at `haystack` (memmem's answer, cheaper).
bool mentions(const void *haystack, size_t size, const char *needle);
// Parses the file: a plain GLB on the fast path (parse_fast) into *fast_doc, setting *fast; else
// with tinygltf into *gltf (the GLB's BIN chunk left where it lies when `in_place`).
bool parse_with_tinygltf(const unsigned char *data, size_t size, const char *name, const std::string &base_dir,
                         FsState *fs_state, doc::Document *fast_doc, bool *fast, tinygltf::Model *gltf,
                         BinInPlace *in_place, TailRead *tail, cb_error *err);

// gltf_files.cpp
// Reads `path` into *out, bounded by max_bytes. With `tail`, a big GLB's BIN chunk is read on
// tail->thread (see TailRead).
template <class Buffer>
bool read_file(const char *path, uint64_t max_bytes, Buffer *out, TailRead *tail, std::string *why, bool *over_limit);
// Maps a model file of 1 MiB and more (see map_model in gltf_files.cpp); false (nothing
// done) where mapping does not apply, and read_file then reads it.
bool map_model(const char *path, uint64_t max_bytes, file_bytes *out, TailRead *tail);
// cb_model.release for keys read in place from a mapped file (ctx: its file_bytes): drops
// the whole pages of the ranges that lie in the mapping; reading them again maps them back.
void release_mapped(void *ctx, const cb_byte_range *ranges, size_t count) noexcept;
// tinygltf's file-system callbacks (user data: the FsState): external buffers are read only
// from inside fs->folder, bounded by fs->max_bytes, and hashed; nothing is written.
bool fs_exists(const std::string &path, void *user);
std::string fs_expand(const std::string &path, void *user);
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user);
bool fs_write(std::string *err, const std::string &path, const std::vector<unsigned char> &bytes, void *user);

// gltf_fast.cpp
// Parses a GLB that needs nothing but its own BIN chunk into `out` (only what the converter
// reads), the BIN chunk left where it lies when `in_place` (else copied into buffer 0); false,
// with `out` untouched, for any file the tinygltf path must load. The first `settled` bytes of
// `data` are not written while it runs (a TailRead may still be filling the rest).
bool parse_fast(const unsigned char *data, size_t size, size_t settled, doc::Document *out, BinInPlace *in_place);
// The fast path's screens (gltf_fast_screen.cpp): a GLB whose chunks tinygltf takes (the JSON
// chunk's length, where the BIN chunk's bytes start and their length), and a JSON text whose
// every number with a fraction or an exponent RapidJSON reads as simdjson does.
bool glb_chunks(const unsigned char *data, size_t size, size_t *json_length, size_t *bin_at, size_t *bin_length);
bool doubles_read_alike(const char *s, size_t n);

// gltf_convert.cpp
// The tinygltf path's result as the converter reads it; the buffers' bytes are moved, not copied.
void doc_from_tinygltf(tinygltf::Model *gltf, doc::Document *out);
int component_size(int type);
int type_components(int type);
bool convert_nodes(Context &c);
bool convert_skins(Context &c);
bool check_joints_in_scene(Context &c);
bool convert_meshes(Context &c);
bool convert_animations(Context &c);

// gltf_materials.cpp
// tinygltf's materials, textures, images (with the bytes of those given by uri) and samplers.
void materials_from_tinygltf(tinygltf::Model *gltf, doc::Document *out);
// The document's materials into the model (before convert_meshes, which points at them). An
// image that cannot be read leaves its texture without one, never an error: only `mesh` uses it.
bool convert_materials(Context &c);
// (gltf_convert.cpp) COLOR_0 of a primitive as RGBA floats, NULL when it has none or it cannot be read.
float *read_colors(Context &c, const doc::Primitive &p, size_t vertex_count);

} // namespace cbgltf

#endif
