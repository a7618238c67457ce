// bench_floor.cpp MODEL.glb - the floor a load cannot go under, measured in the same run as
// crowdbake: read the file into fresh memory (what a plain read() costs, page faults
// included), map it read-only with MAP_POPULATE and touch every page, and parse its JSON chunk
// (the whole glTF JSON for a .gltf) with RapidJSON into a DOM: "parse" with the loader's flags
// (formats/gltf_fast.cpp: a copy parsed in place, full-precision numbers), "parse_plain" with
// RapidJSON's defaults (copied strings, numbers that may be an ulp off). "load" is crowdbake's
// whole load (cb_gltf_load: read, parse, convert, validate) in the same process, its runs taken
// in turns with the floor's. Medians of 7 runs; one JSON object on stdout, in seconds.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
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

int main(int argc, char **argv)
{
    if (argc != 2) return std::fprintf(stderr, "usage: bench_floor MODEL\n"), 2;
    int fd = open(argv[1], O_RDONLY);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) return std::perror(argv[1]), 1;
    size_t size = (size_t)st.st_size;
    std::vector<double> read_s, map_s, parse_s, plain_s, load_s;
    size_t json_bytes = 0;
    unsigned long sum = 0;
    for (int run = 0; run < 7; ++run) {
        double t0 = now();
        unsigned char *buf = static_cast<unsigned char *>(std::malloc(size));
        size_t got = 0;
        while (got < size) {
            ssize_t n = pread(fd, buf + got, size - got, (off_t)got);
            if (n <= 0) return std::fprintf(stderr, "%s: short read\n", argv[1]), 1;
            got += (size_t)n;
        }
        read_s.push_back(now() - t0);
        // The JSON: a GLB's first chunk, or the whole file.
        const char *json = reinterpret_cast<const char *>(buf);
        json_bytes = size;
        if (size >= 20 && std::memcmp(buf, "glTF", 4) == 0) json = reinterpret_cast<const char *>(buf + 20), json_bytes = le32(buf + 12);
        t0 = now();
        std::vector<char> text(json, json + json_bytes);
        text.push_back('\0');
        rapidjson::Document doc;
        doc.ParseInsitu<rapidjson::kParseInsituFlag | rapidjson::kParseFullPrecisionFlag>(text.data());
        parse_s.push_back(now() - t0);
        if (doc.HasParseError()) return std::fprintf(stderr, "%s: JSON parse error\n", argv[1]), 1;
        t0 = now();
        rapidjson::Document plain;
        plain.Parse(json, json_bytes);
        plain_s.push_back(now() - t0);
        std::free(buf);
        t0 = now();
        cb_error err{};
        cb_model *model = cb_gltf_load(argv[1], nullptr, &err);
        load_s.push_back(now() - t0);
        if (!model) return std::fprintf(stderr, "%s\n", err.message), 1;
        cb_model_free(model);
        t0 = now();
        void *map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
        if (map == MAP_FAILED) return std::perror("mmap"), 1;
        for (size_t i = 0; i < size; i += 4096) sum += static_cast<const unsigned char *>(map)[i];
        map_s.push_back(now() - t0);
        munmap(map, size);
    }
    close(fd);
    std::printf("{\"bytes\": %zu, \"json_bytes\": %zu, \"read\": %.6f, \"map_touch\": %.6f, \"parse\": %.6f, "
                "\"parse_plain\": %.6f, \"load\": %.6f, \"touched\": %lu}\n",
                size, json_bytes, median(read_s), median(map_s), median(parse_s), median(plain_s), median(load_s), sum & 1);
    return 0;
}
