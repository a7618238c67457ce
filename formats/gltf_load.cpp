// gltf_load.cpp - the tinygltf adapter: parses with tinygltf (Draco enabled), decodes
// EXT_meshopt_compression with libmeshoptimizer, reads every accessor with bounds checks,
// and hands the core a cb_model of plain C structs.
#include "tinygltf_config.h"

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
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "crowdbake_pal.h"
#include "gltf_load.h"

namespace {

const char kFallbackScheme[] = "crowdbake-meshopt-fallback-";

using Bytes = std::vector<unsigned char>;

struct Span {
    unsigned char *data;
    size_t size;
};

struct Context {
    cb_model *model;
    const tinygltf::Model *gltf;
    std::vector<Span> buffers;   // the bytes of each buffer, which the model owns
    std::vector<bool> copy;      // per accessor: read into a copy even when its floats could be used in place
    cb_limits limits;
    cb_error *err;
    const char *name;
};

std::string first_line(const std::string &s)
{
    size_t start = s.find_first_not_of(" \n\r\t");
    if (start == std::string::npos) return "";
    size_t end = s.find('\n', start);
    return s.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

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
    size_t size() const { return size_; }
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

// Little-endian fields of a GLB header or chunk.
uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

bool is_glb(const unsigned char *data, size_t size) { return size >= 4 && std::memcmp(data, "glTF", 4) == 0; }

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

bool read_all(int fd, unsigned char *to, size_t size, off_t offset)
{
    while (size > 0) {
        ssize_t n = pread(fd, to, size, offset);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        to += n, size -= (size_t)n, offset += n;
    }
    return true;
}

// The bytes before the BIN chunk's data, when the file is a GLB worth splitting: exactly a JSON
// and a BIN chunk, ending at the end of the file, and a JSON that needs no other file or buffer.
size_t split_point(const unsigned char *head, size_t got, size_t size)
{
    if (got < 20 || std::memcmp(head, "glTF", 4) != 0 || le32(head + 8) != size || le32(head + 16) != 0x4E4F534Au)
        return 0;
    size_t json_end = 20 + (size_t)le32(head + 12);
    if (json_end + 8 > got || le32(head + json_end + 4) != 0x004E4942u || json_end + 8 + le32(head + json_end) != size)
        return 0;
    for (const char *needs : {"\"uri\"", "KHR_draco_mesh_compression", "EXT_meshopt_compression"})
        if (memmem(head + 20, json_end - 20, needs, std::strlen(needs))) return 0;
    return json_end + 8;
}

// Reads `path` into *out, bounded by max_bytes. With `tail`, a big GLB's BIN chunk is read on
// tail->thread (see TailRead).
template <class Bytes> bool read_file(const char *path, uint64_t max_bytes, Bytes *out, TailRead *tail, std::string *why)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        *why = fd < 0 ? std::strerror(errno) : "not a regular file";
        if (fd >= 0) close(fd);
        return false;
    }
    if ((uint64_t)st.st_size > max_bytes) {
        close(fd);
        *why = "larger than the " + std::to_string(max_bytes) + "-byte limit (--max-file-size)";
        return false;
    }
    size_t size = (size_t)st.st_size, got = size < (4u << 20) ? size : 20; /* small files at once */
    out->resize(size);
    unsigned char *data = out->data();
    bool ok = read_all(fd, data, got, 0);
    if (ok && got < size && std::memcmp(data, "glTF", 4) == 0) { /* up to the BIN chunk's data */
        size_t want = 20 + (size_t)le32(data + 12) + 8;
        if (want < size) ok = read_all(fd, data + got, want - got, (off_t)got), got = want;
    }
    size_t head = tail && ok && got < size ? split_point(data, got, size) : 0;
    if (ok && head) {
        try {
            tail->head = head;
            tail->thread = std::thread([fd, data, head, size, tail] {
                tail->ok = read_all(fd, data + head, size - head, (off_t)head);
                cbpal_xxh64_init(&tail->hash);
                cbpal_xxh64_update(&tail->hash, data, size);
                close(fd);
            });
            return true;
        } catch (const std::system_error &) {
            tail->head = 0; /* no thread: read it here */
        }
    }
    ok = ok && read_all(fd, data + got, size - got, (off_t)got);
    close(fd);
    if (!ok) *why = "short read";
    return ok;
}

// Model files of 1 MiB and more are mapped read-only with MAP_POPULATE rather than read: their
// pages come from the page cache as they are, where read() into fresh memory zeroes and copies
// each one (for a large rig most of the load's time, in the kernel). The mapping is private and
// made writable once populated, so the loader's in-place writes (rotation keys it normalizes)
// copy only the pages they touch; populating a writable private mapping would copy every page.
// The hash runs on tail->thread while tinygltf parses, when no other file joins it. False
// (nothing done) where mapping does not apply; read_file then reads the file and says why not.
bool map_model(const char *path, uint64_t max_bytes, file_bytes *out, TailRead *tail)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    struct stat st;
    bool fits = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size >= (1 << 20) && (uint64_t)st.st_size <= max_bytes;
    size_t size = fits ? (size_t)st.st_size : 0;
    void *p = fits ? mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0) : MAP_FAILED;
    close(fd);
    if (p == MAP_FAILED) return false;
    if (mprotect(p, size, PROT_READ | PROT_WRITE) != 0) {
        munmap(p, size);
        return false;
    }
    out->adopt_mapping(p, size);
    const unsigned char *data = out->data();
    if (split_point(data, size, size)) {
        try {
            tail->head = size;
            tail->thread = std::thread([data, size, tail] {
                cbpal_xxh64_init(&tail->hash);
                cbpal_xxh64_update(&tail->hash, data, size);
                tail->ok = true;
            });
        } catch (const std::system_error &) {
            tail->head = 0; /* no thread: load() hashes it */
        }
    }
    return true;
}

// ---- file-system callbacks: bounded reads, no shell expansion, meshopt fallback buffers ----

struct FsState {
    uint64_t max_bytes;
    cbpal_xxh64_state *source_hash; // every external file read goes into the model's source hash
    std::vector<std::string> files;  // and into its list of external files, for depfiles
};

bool fs_exists(const std::string &path, void *)
{
    if (path.find(kFallbackScheme) != std::string::npos) return true;
    struct stat st;
    return stat(path.c_str(), &st) == 0;
}

std::string fs_expand(const std::string &path, void *) { return path; }

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user)
{
    FsState *fs = static_cast<FsState *>(user);
    size_t marker = path.find(kFallbackScheme);
    if (marker != std::string::npos) {
        // A meshopt fallback buffer: zeros now, filled by decoding the compressed views.
        unsigned long long bytes = std::strtoull(path.c_str() + marker + sizeof kFallbackScheme - 1, nullptr, 10);
        if (bytes == 0 || bytes > fs->max_bytes) {
            *err = "meshopt fallback buffer of " + std::to_string(bytes) + " bytes is empty or over the size limit";
            return false;
        }
        out->assign((size_t)bytes, 0);
        return true;
    }
    if (!read_file(path.c_str(), fs->max_bytes, out, nullptr, err)) return false;
    cbpal_xxh64_update(fs->source_hash, out->data(), out->size());
    fs->files.push_back(path);
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    *err = "crowdbake never writes through the glTF loader";
    return false;
}

bool skip_image(tinygltf::Image *, const int, std::string *, std::string *, int, int, const unsigned char *, int, void *)
{
    return true; // images are never decoded
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

struct BinInPlace {
    size_t at, length; // length 0: tinygltf read the BIN chunk itself
};

// With `tail` reading the BIN chunk still, only the bytes before it are read until the plain
// parse needs them all.
bool parse_with_tinygltf(const unsigned char *data, size_t size, const char *name, const std::string &base_dir,
                         FsState *fs_state, tinygltf::Model *gltf, BinInPlace *in_place, TailRead *tail, cb_error *err)
{
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
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
        cb_fail(err, CB_ERR_INPUT, "%s: not a valid glTF 2.0 file: %s", name, why.empty() ? "parse failed" : why.c_str());
    }
    return ok;
}

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

bool check_required_extensions(const Context &c)
{
    for (const std::string &ext : c.gltf->extensionsRequired)
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

// ---- accessors ----

int component_size(int type)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

int type_components(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

double read_component(const unsigned char *p, int type, bool normalized)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::fmax(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::fmax(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
        int32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    default: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    }
}

// A view of `count` elements of `elem_size` bytes `stride` apart, checked against its buffer.
bool view_span(const Context &c, int view_index, size_t offset, size_t count, size_t elem_size, size_t stride,
               const char *what, const unsigned char **out)
{
    const tinygltf::Model &g = *c.gltf;
    if (view_index < 0 || view_index >= (int)g.bufferViews.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses bufferView %d, which does not exist", c.name, what, view_index);
        return false;
    }
    const tinygltf::BufferView &view = g.bufferViews[(size_t)view_index];
    if (view.buffer < 0 || view.buffer >= (int)g.buffers.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %d uses buffer %d, which does not exist", c.name, view_index, view.buffer);
        return false;
    }
    const Span &buf = c.buffers[(size_t)view.buffer];
    if (view.byteOffset > buf.size || view.byteLength > buf.size - view.byteOffset) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: bufferView %d spans bytes %zu..%zu, past the end of buffer %d (%zu bytes)", c.name,
                view_index, view.byteOffset, view.byteOffset + view.byteLength, view.buffer, buf.size);
        return false;
    }
    // (count - 1) * stride + elem_size bytes from offset must fit in the view.
    if (count > 0) {
        unsigned long long need = (unsigned long long)(count - 1) * stride + elem_size;
        if (offset > view.byteLength || need > view.byteLength - offset) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s reads %llu bytes from byte %zu of bufferView %d, which has %zu", c.name, what,
                    need, offset, view_index, view.byteLength);
            return false;
        }
    }
    *out = buf.data + view.byteOffset + offset;
    return true;
}

// Reads an accessor into an array of `comps` values per element, applying normalization and
// sparse substitution. Tightly packed, aligned floats are used where they lie in the file's
// buffers (which the model owns); anything else is converted into the model's arena.
template <typename T>
bool read_accessor(const Context &c, int index, int want_comps, const char *what, T **out, size_t *count_out)
{
    const tinygltf::Model &g = *c.gltf;
    if (index < 0 || index >= (int)g.accessors.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses accessor %d, which does not exist", c.name, what, index);
        return false;
    }
    const tinygltf::Accessor &a = g.accessors[(size_t)index];
    int comps = type_components(a.type), csize = component_size(a.componentType);
    if (comps != want_comps || csize == 0) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d has %d components of type %d, expected %d", c.name, what, index,
                comps, a.componentType, want_comps);
        return false;
    }
    if (a.count > c.limits.max_accessor_count) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d claims %zu elements, over the limit of %llu (--max-accessor-count)",
                c.name, what, index, a.count, (unsigned long long)c.limits.max_accessor_count);
        return false;
    }
    size_t elem = (size_t)comps * csize;
    const unsigned char *p = nullptr;
    size_t stride = elem;
    if (a.bufferView >= 0 && a.count > 0) {
        // Bounds first, so a bogus count never drives an allocation.
        if ((size_t)a.bufferView < g.bufferViews.size() && g.bufferViews[(size_t)a.bufferView].byteStride)
            stride = g.bufferViews[(size_t)a.bufferView].byteStride;
        if (stride < elem) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s: bufferView %d has byteStride %zu, smaller than its %zu-byte elements", c.name,
                    what, a.bufferView, stride, elem);
            return false;
        }
        if (!view_span(c, a.bufferView, a.byteOffset, a.count, elem, stride, what, &p)) return false;
    }
    bool packed_floats = p && std::is_same<T, float>::value && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT &&
                         stride == elem && !a.sparse.isSparse;
    if (packed_floats && !c.copy[(size_t)index] && reinterpret_cast<uintptr_t>(p) % alignof(T) == 0) {
        *out = reinterpret_cast<T *>(const_cast<unsigned char *>(p)); // the model owns the buffer; validation may write
        *count_out = a.count;
        return true;
    }
    T *dst = static_cast<T *>(cb_model_alloc(c.model, a.count * (size_t)comps, sizeof(T))); /* zeroed */
    if (!dst) {
        cb_fail(c.err, CB_ERR_INTERNAL, "%s: out of memory reading %s", c.name, what);
        return false;
    }
    if (p && std::is_same<T, float>::value && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && stride == elem) {
        std::memcpy(dst, p, a.count * elem);
    } else if (p) {
        for (size_t i = 0; i < a.count; ++i)
            for (int k = 0; k < comps; ++k) dst[i * comps + k] = (T)read_component(p + i * stride + k * csize, a.componentType, a.normalized);
    }
    if (a.sparse.isSparse && a.sparse.count > 0) {
        size_t n = (size_t)a.sparse.count;
        int isize = component_size(a.sparse.indices.componentType);
        const unsigned char *ip, *vp;
        if (n > a.count || isize == 0 || a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0 ||
            !view_span(c, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset, n, isize, isize, what, &ip) ||
            !view_span(c, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, n, elem, elem, what, &vp)) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d has an invalid sparse block", c.name, what, index);
            return false;
        }
        for (size_t i = 0; i < n; ++i) {
            double target = read_component(ip + i * isize, a.sparse.indices.componentType, false);
            if (target < 0 || target >= (double)a.count) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: %s: accessor %d sparse index %.0f is past its %zu elements", c.name, what,
                        index, target, a.count);
                return false;
            }
            for (int k = 0; k < comps; ++k)
                dst[(size_t)target * comps + k] = (T)read_component(vp + i * elem + k * csize, a.componentType, a.normalized);
        }
    }
    *out = dst;
    *count_out = a.count;
    return true;
}

// ---- conversion to the core's structs ----

const char *name_or(cb_model *m, const std::string &name, const char *prefix, size_t index)
{
    if (!name.empty()) return cb_model_strdup(m, name.c_str());
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s_%zu", prefix, index);
    return cb_model_strdup(m, buf);
}

bool convert_nodes(Context &c)
{
    const auto &nodes = c.gltf->nodes;
    cb_model *m = c.model;
    m->node_count = (uint32_t)nodes.size();
    m->nodes = static_cast<cb_node *>(cb_model_alloc(m, nodes.size(), sizeof(cb_node)));
    for (size_t i = 0; i < nodes.size(); ++i) m->nodes[i].parent = -1;
    for (size_t i = 0; i < nodes.size(); ++i) {
        const tinygltf::Node &src = nodes[i];
        cb_node *n = &m->nodes[i];
        n->name = name_or(m, src.name, "node", i);
        for (int child : src.children) {
            if (child < 0 || child >= (int)nodes.size()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: node %zu (%s) lists child %d, which does not exist", c.name, i, n->name, child);
                return false;
            }
            if (m->nodes[child].parent != -1 || (size_t)child == i) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: node %d has two parents (%d and %zu); glTF nodes form a tree", c.name, child,
                        m->nodes[child].parent, i);
                return false;
            }
            m->nodes[child].parent = (int32_t)i;
        }
        n->rotation[3] = 1;
        n->scale[0] = n->scale[1] = n->scale[2] = 1;
        if (src.matrix.size() == 16) {
            n->has_matrix = true;
            for (int k = 0; k < 16; ++k) n->matrix[k] = src.matrix[k];
            continue; // the core derives TRS from the matrix
        }
        if (src.translation.size() == 3)
            for (int k = 0; k < 3; ++k) n->translation[k] = src.translation[k];
        if (src.scale.size() == 3)
            for (int k = 0; k < 3; ++k) n->scale[k] = src.scale[k];
        if (src.rotation.size() == 4)
            for (int k = 0; k < 4; ++k) n->rotation[k] = src.rotation[k]; // normalized by the core
    }
    return true;
}

// glTF wants every joint in the scene that is rendered; a joint elsewhere would be animated
// in a hierarchy the runtime never sees.
bool check_joints_in_scene(Context &c)
{
    const tinygltf::Model &g = *c.gltf;
    if (g.scenes.empty()) return true;
    int scene = g.defaultScene >= 0 && g.defaultScene < (int)g.scenes.size() ? g.defaultScene : 0;
    const std::vector<int> &roots = g.scenes[(size_t)scene].nodes;
    for (uint32_t s = 0; s < c.model->skin_count; ++s) {
        const cb_skin *skin = &c.model->skins[s];
        for (uint32_t j = 0; j < skin->joint_count; ++j) {
            int32_t n = skin->joints[j];
            if (n < 0 || n >= (int32_t)c.model->node_count) continue; // reported by validation
            uint32_t steps = 0;
            while (c.model->nodes[n].parent >= 0 && steps++ < c.model->node_count) n = c.model->nodes[n].parent;
            if (std::find(roots.begin(), roots.end(), n) == roots.end()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: skin %u joint %u (%s) is not in scene %d: its root node %d (%s) is not one "
                        "of the scene's nodes; add it to the scene", c.name, s, j, c.model->nodes[skin->joints[j]].name,
                        scene, n, c.model->nodes[n].name);
                return false;
            }
        }
    }
    return true;
}

bool convert_skins(Context &c)
{
    const auto &skins = c.gltf->skins;
    cb_model *m = c.model;
    m->skin_count = (uint32_t)skins.size();
    m->skins = static_cast<cb_skin *>(cb_model_alloc(m, skins.size(), sizeof(cb_skin)));
    for (size_t s = 0; s < skins.size(); ++s) {
        const tinygltf::Skin &src = skins[s];
        cb_skin *skin = &m->skins[s];
        skin->name = name_or(m, src.name, "skin", s);
        skin->skeleton = src.skeleton;
        if (src.joints.size() > c.limits.max_joints) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: skin %zu (%s) has %zu joints, over the limit of %u (--max-joints)", c.name, s,
                    skin->name, src.joints.size(), c.limits.max_joints);
            return false;
        }
        skin->joint_count = (uint32_t)src.joints.size();
        skin->joints = static_cast<int32_t *>(cb_model_alloc(m, src.joints.size(), sizeof(int32_t)));
        skin->inverse_bind = static_cast<double *>(cb_model_alloc(m, src.joints.size() * 16, sizeof(double)));
        if (!skin->joints || !skin->inverse_bind) return false;
        for (size_t j = 0; j < src.joints.size(); ++j) {
            skin->joints[j] = src.joints[j];
            for (int k = 0; k < 16; ++k) skin->inverse_bind[j * 16 + k] = k % 5 == 0 ? 1.0 : 0.0; // identity
        }
        if (src.inverseBindMatrices >= 0) {
            double *ibm;
            size_t count;
            std::string what = "skin " + std::to_string(s) + " inverseBindMatrices";
            if (!read_accessor(c, src.inverseBindMatrices, 16, what.c_str(), &ibm, &count)) return false;
            if (count < src.joints.size()) {
                cb_fail(c.err, CB_ERR_INPUT, "%s: skin %zu (%s) has %zu inverse bind matrices for %zu joints", c.name, s,
                        skin->name, count, src.joints.size());
                return false;
            }
            std::memcpy(skin->inverse_bind, ibm, src.joints.size() * 16 * sizeof(double));
        }
    }
    return true;
}

bool convert_primitive(Context &c, size_t node_index, const tinygltf::Primitive &p, std::vector<cb_primitive> *out)
{
    auto pos = p.attributes.find("POSITION"), jnt = p.attributes.find("JOINTS_0"), wgt = p.attributes.find("WEIGHTS_0");
    if (pos == p.attributes.end() || jnt == p.attributes.end() || wgt == p.attributes.end()) return true; // not skinned
    const tinygltf::Node &node = c.gltf->nodes[node_index];
    std::string where = "mesh node " + std::to_string(node_index) + " (" + node.name + ")";
    float *positions, *weights, *normals;
    double *joints;
    uint32_t *indices;
    size_t n, nj, nw, nn, ni;
    if (!read_accessor(c, pos->second, 3, (where + " POSITION").c_str(), &positions, &n) ||
        !read_accessor(c, jnt->second, 4, (where + " JOINTS_0").c_str(), &joints, &nj) ||
        !read_accessor(c, wgt->second, 4, (where + " WEIGHTS_0").c_str(), &weights, &nw))
        return false;
    if (nj != n || nw != n) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has %zu positions but %zu joints and %zu weights", c.name, where.c_str(), n, nj, nw);
        return false;
    }
    uint16_t *joints16 = static_cast<uint16_t *>(cb_model_alloc(c.model, n * 4, sizeof(uint16_t)));
    if (!joints16) return false;
    for (size_t i = 0; i < n * 4; ++i) {
        if (joints[i] < 0 || joints[i] > 65535) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: %s has joint index %.0f outside 0..65535", c.name, where.c_str(), joints[i]);
            return false;
        }
        joints16[i] = (uint16_t)joints[i];
    }
    cb_primitive prim{};
    prim.node = (int32_t)node_index;
    prim.skin = node.skin;
    prim.vertex_count = (uint32_t)n;
    auto nrm = p.attributes.find("NORMAL");
    if (nrm != p.attributes.end()) {
        if (!read_accessor(c, nrm->second, 3, (where + " NORMAL").c_str(), &normals, &nn)) return false;
        if (nn == n) prim.normals = normals;
    }
    auto uv = p.attributes.find("TEXCOORD_0");
    if (uv != p.attributes.end()) { /* only `mesh` carries it: a broken one is left out, never an error */
        float *texcoords;
        size_t nt;
        cb_error uv_err{};
        Context quiet = c;
        quiet.err = &uv_err;
        if (read_accessor(quiet, uv->second, 2, (where + " TEXCOORD_0").c_str(), &texcoords, &nt) && nt == n)
            prim.texcoords = texcoords;
    }
    if (p.indices >= 0) {
        if (!read_accessor(c, p.indices, 1, (where + " indices").c_str(), &indices, &ni)) return false;
        prim.index_count = (uint32_t)ni;
        prim.indices = indices;
    }
    for (auto &a : p.attributes) { /* every attribute, as the file types it: what a runtime uploads */
        const tinygltf::Accessor &acc = c.gltf->accessors[(size_t)a.second];
        uint32_t elem = (uint32_t)(type_components(acc.type) * component_size(acc.componentType));
        prim.vertex_bytes += (elem + 3) / 4 * 4;
    }
    if (p.indices >= 0) prim.index_bytes = component_size(c.gltf->accessors[(size_t)p.indices].componentType) == 4 ? 4 : 2;
    prim.positions = positions;
    prim.joints = joints16;
    prim.weights = weights;
    out->push_back(prim);
    return true;
}

bool convert_meshes(Context &c)
{
    const tinygltf::Model &g = *c.gltf;
    std::vector<cb_primitive> prims;
    for (size_t i = 0; i < g.nodes.size(); ++i) {
        const tinygltf::Node &node = g.nodes[i];
        if (node.mesh < 0 || node.skin < 0) continue;
        if (node.mesh >= (int)g.meshes.size() || node.skin >= (int)g.skins.size()) {
            cb_fail(c.err, CB_ERR_INPUT, "%s: node %zu uses mesh %d / skin %d, which do not exist", c.name, i, node.mesh, node.skin);
            return false;
        }
        for (const tinygltf::Primitive &p : g.meshes[(size_t)node.mesh].primitives)
            if (!convert_primitive(c, i, p, &prims)) return false;
    }
    cb_model *m = c.model;
    m->primitive_count = (uint32_t)prims.size();
    m->primitives = static_cast<cb_primitive *>(cb_model_alloc(m, prims.size(), sizeof(cb_primitive)));
    std::copy(prims.begin(), prims.end(), m->primitives);
    return true;
}

bool parse_interpolation(const std::string &s, cb_interp *out)
{
    if (s.empty() || s == "LINEAR") *out = CB_INTERP_LINEAR;
    else if (s == "STEP") *out = CB_INTERP_STEP;
    else if (s == "CUBICSPLINE") *out = CB_INTERP_CUBICSPLINE;
    else return false;
    return true;
}

bool convert_channel(Context &c, size_t a, size_t ci, const tinygltf::Animation &src, std::vector<cb_channel> *out)
{
    const tinygltf::AnimationChannel &ch = src.channels[ci];
    const std::string &path = ch.target_path;
    std::string where = "clip '" + std::string(c.model->animations[a].name) + "' channel " + std::to_string(ci);
    if (path == "weights") {
        c.model->ignored_morph_channels++;
        return true;
    }
    cb_channel dst{};
    if (path == "translation") dst.path = CB_PATH_TRANSLATION;
    else if (path == "rotation") dst.path = CB_PATH_ROTATION;
    else if (path == "scale") dst.path = CB_PATH_SCALE;
    else {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s animates '%s'; glTF 2.0 allows translation, rotation, scale and weights", c.name,
                where.c_str(), path.c_str());
        return false;
    }
    if (ch.target_node < 0) return true; // targets something else (an extension); not a joint
    if (ch.sampler < 0 || ch.sampler >= (int)src.samplers.size()) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s uses sampler %d, which does not exist", c.name, where.c_str(), ch.sampler);
        return false;
    }
    const tinygltf::AnimationSampler &s = src.samplers[(size_t)ch.sampler];
    if (!parse_interpolation(s.interpolation, &dst.interp)) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has interpolation '%s'; use LINEAR, STEP or CUBICSPLINE", c.name, where.c_str(),
                s.interpolation.c_str());
        return false;
    }
    dst.node = ch.target_node;
    int comps = dst.path == CB_PATH_ROTATION ? 4 : 3;
    float *times, *values;
    size_t nt, nv;
    if (!read_accessor(c, s.input, 1, (where + " key times").c_str(), &times, &nt) ||
        !read_accessor(c, s.output, comps, (where + " values").c_str(), &values, &nv))
        return false;
    size_t per_key = dst.interp == CB_INTERP_CUBICSPLINE ? 3 : 1;
    if (nv != nt * per_key) {
        cb_fail(c.err, CB_ERR_INPUT, "%s: %s has %zu key times but %zu values (expected %zu)", c.name, where.c_str(), nt, nv,
                nt * per_key);
        return false;
    }
    dst.key_count = (uint32_t)nt;
    dst.times = times;
    dst.values = values;
    out->push_back(dst);
    return true;
}

bool convert_animations(Context &c)
{
    const auto &anims = c.gltf->animations;
    cb_model *m = c.model;
    m->animation_count = (uint32_t)anims.size();
    m->animations = static_cast<cb_animation *>(cb_model_alloc(m, anims.size(), sizeof(cb_animation)));
    for (size_t a = 0; a < anims.size(); ++a) {
        cb_animation *dst = &m->animations[a];
        dst->name = name_or(m, anims[a].name, "animation", a);
        std::vector<cb_channel> channels;
        for (size_t ci = 0; ci < anims[a].channels.size(); ++ci)
            if (!convert_channel(c, a, ci, anims[a], &channels)) return false;
        dst->channel_count = (uint32_t)channels.size();
        dst->channels = static_cast<cb_channel *>(cb_model_alloc(m, channels.size(), sizeof(cb_channel)));
        std::copy(channels.begin(), channels.end(), dst->channels);
    }
    return true;
}

// ---- buffers: owned by the model, read in place ----

// The bytes an accessor reads (its sparse blocks included), for finding overlaps.
struct ByteRange {
    int buffer;
    size_t begin, end, accessor;
};

void add_span(const tinygltf::Model &g, int view_index, size_t offset, size_t bytes, size_t accessor, std::vector<ByteRange> *out)
{
    if (view_index < 0 || (size_t)view_index >= g.bufferViews.size() || bytes == 0) return;
    const tinygltf::BufferView &v = g.bufferViews[(size_t)view_index];
    size_t begin = v.byteOffset + offset; // bounds are checked when read; here only overlap matters
    out->push_back(ByteRange{v.buffer, begin, begin + std::min(bytes, v.byteLength), accessor});
}

// cb_model_validate normalizes rotation keys where they lie. Read in place, that write must
// not reach bytes that another channel or accessor reads, so such rotation keys are copied:
// those used by several channels and those whose bytes overlap another accessor's.
std::vector<bool> accessors_to_copy(const tinygltf::Model &g)
{
    size_t n = g.accessors.size();
    std::vector<unsigned> rotation_uses(n);
    for (const auto &anim : g.animations)
        for (const auto &ch : anim.channels)
            if (ch.target_path == "rotation" && ch.sampler >= 0 && (size_t)ch.sampler < anim.samplers.size()) {
                int out = anim.samplers[(size_t)ch.sampler].output;
                if (out >= 0 && (size_t)out < n) rotation_uses[(size_t)out]++;
            }
    std::vector<bool> copy(n);
    std::vector<ByteRange> spans;
    for (size_t i = 0; i < n; ++i) {
        const tinygltf::Accessor &a = g.accessors[i];
        copy[i] = rotation_uses[i] > 1;
        size_t elem = (size_t)type_components(a.type) * component_size(a.componentType);
        size_t stride = elem;
        if (a.bufferView >= 0 && (size_t)a.bufferView < g.bufferViews.size() && g.bufferViews[(size_t)a.bufferView].byteStride)
            stride = g.bufferViews[(size_t)a.bufferView].byteStride;
        if (a.count > 0 && a.count <= SIZE_MAX / (stride + 1))
            add_span(g, a.bufferView, a.byteOffset, (a.count - 1) * stride + elem, i, &spans);
        if (a.sparse.isSparse && a.sparse.count > 0) {
            size_t sparse = (size_t)a.sparse.count;
            if (a.sparse.indices.byteOffset >= 0)
                add_span(g, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset,
                         sparse * component_size(a.sparse.indices.componentType), i, &spans);
            if (a.sparse.values.byteOffset >= 0)
                add_span(g, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, sparse * elem, i, &spans);
        }
    }
    std::sort(spans.begin(), spans.end(),
              [](const ByteRange &x, const ByteRange &y) { return x.buffer != y.buffer ? x.buffer < y.buffer : x.begin < y.begin; });
    std::vector<ByteRange> open; // earlier spans of this buffer that reach past the current one's start
    for (const ByteRange &s : spans) {
        open.erase(std::remove_if(open.begin(), open.end(),
                                  [&s](const ByteRange &o) { return o.buffer != s.buffer || o.end <= s.begin; }),
                   open.end());
        for (const ByteRange &o : open)
            if (o.accessor != s.accessor && (rotation_uses[o.accessor] || rotation_uses[s.accessor]))
                copy[o.accessor] = copy[s.accessor] = true;
        open.push_back(s);
    }
    return copy;
}

// What the model keeps of the file: tinygltf's buffers, and the file's own bytes when the BIN
// chunk is read where it lies.
struct OwnedBytes {
    std::vector<Bytes> buffers;
    file_bytes file;
};

// Hands the buffers' bytes to the model, so accessors can be read in place.
bool adopt_buffers(Context &c, tinygltf::Model *gltf, file_bytes *file, const BinInPlace &bin)
{
    std::unique_ptr<OwnedBytes> owned(new OwnedBytes());
    owned->buffers.reserve(gltf->buffers.size());
    for (tinygltf::Buffer &b : gltf->buffers) {
        owned->buffers.push_back(std::move(b.data));
        c.buffers.push_back(Span{owned->buffers.back().data(), owned->buffers.back().size()});
    }
    if (bin.length && !c.buffers.empty()) {
        owned->file = std::move(*file);
        c.buffers[0] = Span{owned->file.data() + bin.at, bin.length};
    }
    if (!cb_arena_adopt(c.model->arena, owned.get(), [](void *p) { delete static_cast<OwnedBytes *>(p); })) {
        cb_fail(c.err, CB_ERR_INTERNAL, "%s: out of memory", c.name);
        return false;
    }
    owned.release(); // the model's now
    c.copy = accessors_to_copy(*gltf);
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
    tinygltf::Model gltf;
    cbpal_xxh64_state source_hash;
    cbpal_xxh64_init(&source_hash);
    if (!tail) cbpal_xxh64_update(&source_hash, data, size); /* else the tail's thread hashes the file */
    FsState fs{c.limits.max_file_bytes, &source_hash, {}};
    BinInPlace bin{0, 0};
    bool parsed = parse_with_tinygltf(data, size, name, base_dir, &fs, &gltf, file ? &bin : nullptr, tail, err);
    if (tail) {
        tail->wait();
        if (parsed && !tail->ok) cb_fail(err, CB_ERR_IO, "%s: cannot read: short read", name);
        parsed = parsed && tail->ok;
        source_hash = tail->hash; /* no other file was read: the split needs a JSON without uris */
    }
    if (!parsed) return nullptr;
    c.gltf = &gltf;
    if (!check_required_extensions(c) || !decode_meshopt(c, &gltf)) return nullptr;
    c.model = cb_model_create(name);
    if (!c.model) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", name);
        return nullptr;
    }
    if (!adopt_buffers(c, &gltf, file, bin)) {
        cb_model_free(c.model);
        return nullptr;
    }
    if (!convert_nodes(c) || !convert_skins(c) || !check_joints_in_scene(c) || !convert_meshes(c) || !convert_animations(c) ||
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
        return load(data, size, file, tail, name, base_dir ? base_dir : "/nonexistent-crowdbake-dir", limits, err);
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
        if (!map_model(path, l.max_file_bytes, &bytes, &tail) && !read_file(path, l.max_file_bytes, &bytes, &tail, &why)) {
            cb_fail(err, CB_ERR_IO, "%s: cannot read: %s", path, why.c_str());
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
    dir = slash == std::string::npos ? "." : dir.substr(0, slash);
    return load_guarded(bytes.data(), bytes.size(), &bytes, tail.head ? &tail : nullptr, path, dir.c_str(), &l, err);
}
