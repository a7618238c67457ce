// bench_floor.cpp MODEL.glb - the floor a load cannot go under, measured in the same run as
// crowdbake: read the file into memory, map it read-only with MAP_POPULATE and touch every
// page, and parse its JSON chunk (the whole glTF JSON for a .gltf) with RapidJSON into a DOM:
// "parse" with the loader's flags (formats/gltf_fast.cpp: a copy parsed in place,
// full-precision numbers), "parse_plain" with RapidJSON's defaults (copied strings, numbers that
// may be an ulp off). "load" is crowdbake's whole load (cb_gltf_load: read, parse, convert,
// validate), its runs taken in turns with the floor's. Medians of 7 runs; one JSON object on
// stdout, in seconds.
//
// Each side runs in a fresh process of its own (forked from this one, which allocates next to
// nothing), as a bake does: "read" reads into fresh memory (page faults included), then
// "parse" and "parse_plain" follow; "load" runs alone in another. On the VMs this runs on,
// first-touched memory costs far more than reused memory, so measured in one process each side
// paid for what the other had left in (or taken out of) the heap: the read was 4 to 36 ms for
// the same 25 MB depending on the loads before it, and the load's own allocations likewise.
// Two reads with no such state, in this process, are reported beside them: "read_warm", into a
// page-aligned buffer read into before (no page faults: the kernel's copy alone), and
// "map_touch". (A read into a buffer 16 bytes past a page boundary, where glibc puts a large
// malloc, took 17 ms where the same read page-aligned took 4: the buffers here are aligned.)
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <rapidjson/document.h>

#include "crowdbake/gltf.h"

static double now()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

static double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

static uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

static bool read_all(int fd, unsigned char *to, size_t size)
{
    for (size_t got = 0; got < size;) {
        ssize_t n = pread(fd, to + got, size - got, (off_t)got);
        if (n <= 0) return false;
        got += (size_t)n;
    }
    return true;
}

static unsigned char *map_anonymous(size_t size) // page-aligned, fresh
{
    void *p = mmap(nullptr, size ? size : 1, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    return p == MAP_FAILED ? nullptr : static_cast<unsigned char *>(p);
}

// The floor, in a fresh process: seconds of read, parse and parse_plain into out[0..2].
static bool floor_run(const char *path, int fd, size_t size, double out[3])
{
    double t0 = now();
    unsigned char *buf = map_anonymous(size);
    if (!buf || !read_all(fd, buf, size)) return std::fprintf(stderr, "%s: short read\n", path), false;
    out[0] = now() - t0;
    // The JSON: a GLB's first chunk, or the whole file.
    const char *json = reinterpret_cast<const char *>(buf);
    size_t json_bytes = size;
    if (size >= 20 && std::memcmp(buf, "glTF", 4) == 0) json = reinterpret_cast<const char *>(buf + 20), json_bytes = le32(buf + 12);
    t0 = now();
    std::vector<char> text(json, json + json_bytes);
    text.push_back('\0');
    rapidjson::Document doc;
    doc.ParseInsitu<rapidjson::kParseInsituFlag | rapidjson::kParseFullPrecisionFlag>(text.data());
    out[1] = now() - t0;
    if (doc.HasParseError()) return std::fprintf(stderr, "%s: JSON parse error\n", path), false;
    t0 = now();
    rapidjson::Document plain;
    plain.Parse(json, json_bytes);
    out[2] = now() - t0;
    return true;
}

// crowdbake's load, in a fresh process: its seconds into out[0].
static bool load_run(const char *path, double out[1])
{
    double t0 = now();
    cb_error err{};
    cb_model *model = cb_gltf_load(path, nullptr, &err);
    out[0] = now() - t0;
    if (!model) return std::fprintf(stderr, "%s\n", err.message), false;
    cb_model_free(model);
    return true;
}

// Runs f(out) in a child process; its `count` results come back through a pipe.
template <class F> static bool in_child(F f, double *out, size_t count)
{
    int fds[2];
    if (pipe(fds) != 0) return std::perror("pipe"), false;
    pid_t pid = fork();
    if (pid < 0) return std::perror("fork"), false;
    if (pid == 0) {
        close(fds[0]);
        bool ok = f(out) && write(fds[1], out, count * sizeof *out) == (ssize_t)(count * sizeof *out);
        _exit(ok ? 0 : 1);
    }
    close(fds[1]);
    ssize_t got = read(fds[0], out, count * sizeof *out);
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    return got == (ssize_t)(count * sizeof *out) && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

int main(int argc, char **argv)
{
    if (argc != 2) return std::fprintf(stderr, "usage: bench_floor MODEL\n"), 2;
    const char *path = argv[1];
    int fd = open(path, O_RDONLY);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) return std::perror(path), 1;
    size_t size = (size_t)st.st_size;
    size_t json_bytes = size;
    unsigned char *warm = map_anonymous(size);
    // Not shared with the children: a fork would make every page copy-on-write, a fault at each
    // next write.
    if (!warm || madvise(warm, size ? size : 1, MADV_DONTFORK) != 0 || !read_all(fd, warm, size))
        return std::fprintf(stderr, "%s: short read\n", path), 1; // its pages faulted in
    if (size >= 20 && std::memcmp(warm, "glTF", 4) == 0) json_bytes = le32(warm + 12);
    std::vector<double> read_s, parse_s, plain_s, load_s, warm_s, map_s;
    unsigned long sum = 0;
    for (int run = 0; run < 7; ++run) {
        double f[3], l[1];
        if (!in_child([&](double *out) { return floor_run(path, fd, size, out); }, f, 3)) return 1;
        read_s.push_back(f[0]), parse_s.push_back(f[1]), plain_s.push_back(f[2]);
        if (!in_child([&](double *out) { return load_run(path, out); }, l, 1)) return 1;
        load_s.push_back(l[0]);
        double t0 = now();
        if (!read_all(fd, warm, size)) return std::fprintf(stderr, "%s: short read\n", path), 1;
        warm_s.push_back(now() - t0);
        t0 = now();
        void *map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
        if (map == MAP_FAILED) return std::perror("mmap"), 1;
        for (size_t i = 0; i < size; i += 4096) sum += static_cast<const unsigned char *>(map)[i];
        map_s.push_back(now() - t0);
        munmap(map, size);
    }
    close(fd);
    munmap(warm, size ? size : 1);
    std::printf("{\"bytes\": %zu, \"json_bytes\": %zu, \"read\": %.6f, \"read_warm\": %.6f, \"map_touch\": %.6f, "
                "\"parse\": %.6f, \"parse_plain\": %.6f, \"load\": %.6f, \"touched\": %lu}\n",
                size, json_bytes, median(read_s), median(warm_s), median(map_s), median(parse_s), median(plain_s),
                median(load_s), sum & 1);
    return 0;
}
