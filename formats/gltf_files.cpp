// gltf_files.cpp - the model's file and the files it names: bounded reads, a big model mapped
// and read ahead on a second thread, the mapping's pages released after use, and the external
// buffers tinygltf asks for, read only from inside the model's folder.
#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "gltf_parts.h"

namespace cbgltf {
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
    for (const char *needs : {"\"uri\"", "_compression"}) /* Draco and meshopt */
        if (mentions(head + 20, json_end - 20, needs)) return 0;
    return json_end + 8;
}

// Reads `path` into *out, bounded by max_bytes (*over_limit, when given, says a refusal was that
// bound's). With `tail`, a big GLB's BIN chunk is read on tail->thread (see TailRead).
template <class Bytes>
bool read_file(const char *path, uint64_t max_bytes, Bytes *out, TailRead *tail, std::string *why, bool *over_limit)
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
        *why = "larger than the " + std::to_string(max_bytes) + "-byte file size limit; raise the limit";
        if (over_limit) *over_limit = true;
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

// ---- file-system callbacks: bounded reads, no shell expansion, meshopt fallback buffers ----

// Whether `path` starts with `folder` and what follows is a relative path (a uri tinygltf
// joined to the folder: folder + "/" + uri).
static bool under_folder(const std::string &path, const std::string &folder, size_t *rest)
{
    if (folder.empty() || path.compare(0, folder.size(), folder) != 0) return false;
    size_t at = folder.size();
    if (folder.back() != '/' && (at >= path.size() || path[at++] != '/')) return false;
    *rest = at;
    return true;
}

// Whether `path` names a file inside the model's folder. tinygltf joins each decoded uri to the
// model's folder and then to the working directory, and joins an absolute uri or one with ".."
// as it is: any of them would read a file outside the folder, one the model's author chose
// (a model downloaded with a "../../.ssh/id_rsa" buffer would put that file's bytes in a bake).
static bool inside_folder(const std::string &path, const std::string &folder)
{
    size_t at;
    if (!under_folder(path, folder, &at) || at >= path.size() || path[at] == '/') return false; // empty or absolute
    for (size_t end; at <= path.size(); at = end + 1) {
        end = std::min(path.find('/', at), path.size());
        if (end - at == 2 && path.compare(at, 2, "..") == 0) return false;
    }
    return true;
}

bool fs_exists(const std::string &path, void *user)
{
    const FsState *fs = static_cast<const FsState *>(user);
    if (path.find(kFallbackScheme) != std::string::npos) return true;
    size_t rest;
    if (!inside_folder(path, fs->folder)) /* fs_read says why, unless it is the working-directory try */
        return under_folder(path, fs->folder, &rest);
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
            fs->over_limit |= bytes > fs->max_bytes;
            *err = "meshopt fallback buffer of " + std::to_string(bytes) + " bytes is empty or over the file size limit";
            return false;
        }
        out->assign((size_t)bytes, 0);
        return true;
    }
    if (!inside_folder(path, fs->folder)) {
        *err = "the uri leads outside the model's folder (an absolute path or \"..\"); crowdbake reads only files in "
               "the model's folder or below it: put the file there and give its relative path";
        return false;
    }
    if (!read_file(path.c_str(), fs->max_bytes, out, nullptr, err, &fs->over_limit)) return false;
    cbpal_xxh64_update(fs->source_hash, out->data(), out->size());
    fs->files.push_back(path);
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    *err = "crowdbake never writes through the glTF loader";
    return false;
}

// Maps the whole pages of [p, p + n) into the page tables, from the page cache, without
// touching their bytes (MADV_POPULATE_READ, Linux 5.14; a hint: elsewhere the reads that follow
// fault them in).
static void populate(const unsigned char *p, size_t n)
{
#if defined(MADV_POPULATE_READ)
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE), from = (uintptr_t)p & ~(page - 1);
    if (page && !(page & (page - 1))) madvise(reinterpret_cast<void *>(from), (uintptr_t)p + n - from, MADV_POPULATE_READ);
#else
    (void)p, (void)n;
#endif
}

// The model file itself is read into huge pages (external buffers into tinygltf's vectors).
// Model files of 1 MiB and more are mapped read-only rather than read: their pages come from
// the page cache as they are, where read() into fresh memory zeroes and copies each one (for a
// large rig most of the load's time, in the kernel). The mapping stays read-only: the loader
// never writes into it (rotation keys it normalizes are copied first, cb_model_validate), so a
// stray write faults instead of changing a key, and every page is the page cache's copy of the
// file, which release_mapped can drop and a read maps back.
// A GLB that needs no other file is populated and hashed on tail->thread, a megabyte at a time,
// while the JSON chunk is parsed (the page tables of a 25 MB rig are 3 ms of serial time
// otherwise); any other file is populated here. False (nothing done) where mapping does not
// apply; read_file then reads the file and says why not.
bool map_model(const char *path, uint64_t max_bytes, file_bytes *out, TailRead *tail)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    struct stat st;
    bool fits = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size >= (1 << 20) && (uint64_t)st.st_size <= max_bytes;
    size_t size = fits ? (size_t)st.st_size : 0;
    void *p = fits ? mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
    close(fd);
    if (p == MAP_FAILED) return false;
    out->adopt_mapping(p, size);
    const unsigned char *data = out->data();
    if (split_point(data, size, size)) {
        try {
            tail->head = size;
            tail->thread = std::thread([data, size, tail] {
                const size_t chunk = (size_t)1 << 20; /* populated just before it is hashed */
                cbpal_xxh64_init(&tail->hash);
                for (size_t at = 0; at < size; at += chunk) {
                    size_t n = std::min(chunk, size - at);
                    populate(data + at, n);
                    cbpal_xxh64_update(&tail->hash, data + at, n);
                }
                tail->ok = true;
            });
            return true;
        } catch (const std::system_error &) {
            tail->head = 0; /* no thread: load() hashes it */
        }
    }
    populate(data, size);
    return true;
}

// cb_model.release for a model that reads its keys where they lie in map_model's mapping
// (ctx: the model's file_bytes). A bake reads a clip's keys while it samples the clip and again
// while it measures it; in between, and after, their pages only add to the peak memory (for a
// big rig the keys are most of the file, as large as the stash). The whole pages inside the
// ranges, and inside the mapping, are dropped (MADV_DONTNEED): the mapping is read-only and
// never written, so reading them again maps the page cache's copy of the file back (a minor
// fault, no zeroing, no copy), the same bytes. Ranges elsewhere (keys copied into the model's
// arena, tinygltf's buffers) are left alone: dropping those would lose them. Called from C:
// nothing may throw out of it, and without memory it does nothing (it is a hint).
void release_mapped(void *ctx, const cb_byte_range *ranges, size_t count) noexcept
{
    const file_bytes *file = static_cast<const file_bytes *>(ctx);
    uintptr_t begin = reinterpret_cast<uintptr_t>(file->bytes()), end = begin + file->size();
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
    if (!file->mapped() || page == 0 || (page & (page - 1))) return;
    std::vector<std::pair<uintptr_t, uintptr_t>> runs; // [from, to) clipped to the mapping
    try {
        runs.reserve(count);
    } catch (const std::bad_alloc &) {
        return;
    }
    for (size_t i = 0; i < count; ++i) {
        uintptr_t from = reinterpret_cast<uintptr_t>(ranges[i].ptr);
        if (from >= end || ranges[i].bytes > end - from || from < begin) continue; // not all in the mapping
        runs.emplace_back(from, from + ranges[i].bytes);                         // reserved: no allocation
    }
    if (!std::is_sorted(runs.begin(), runs.end())) std::sort(runs.begin(), runs.end()); // mostly in file order
    for (size_t i = 0; i < runs.size();) {
        // Runs less than a page apart join: a clip's accessors usually lie one after another,
        // each smaller than a page, with a few bytes of padding between them.
        uintptr_t from = runs[i].first, to = runs[i].second;
        for (++i; i < runs.size() && runs[i].first < to + page; ++i) to = std::max(to, runs[i].second);
        uintptr_t first = (from + page - 1) & ~(page - 1), last = to & ~(page - 1); // whole pages only
        if (first < last) madvise(reinterpret_cast<void *>(first), last - first, MADV_DONTNEED);
    }
}

template bool read_file<file_bytes>(const char *path, uint64_t max_bytes, file_bytes *out, TailRead *tail, std::string *why,
                                     bool *over_limit);


} // namespace cbgltf
