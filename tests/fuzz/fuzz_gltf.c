/* fuzz_gltf.c - libFuzzer target: the glTF loader the way every command runs it, through a file
 * (cb_gltf_load), then sampling and a small bake of whatever loads.
 *
 * Each input loads twice from a folder of its own: as it is (read into memory), and padded past
 * 1 MiB (a GLB's BIN chunk grown, a .gltf's JSON followed by spaces), so the file is mapped, a
 * plain GLB is read ahead and hashed on a second thread, its BIN chunk read in place and its
 * pages released after each clip is baked (release_mapped).
 *
 * An input may carry the files its uris name: after the model's bytes, each file is a line
 * FILE_MARKER NAME "\n" and its bytes. NAME is a file name, written beside the model, or
 * "../" and a file name, written in the folder above the model's: a model that loads having
 * read any file outside its folder (through "../", an absolute path or the working directory)
 * is a finding (abort), as is any sanitizer report. */
#define _DEFAULT_SOURCE /* mkdtemp, realpath */
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "crowdbake/gltf.h"
#include "crowdbake/palette.h"

#define FILE_MARKER "#%crowdbake-fuzz-file:"
#define MAX_FILES 4
#define MAPPED_SIZE ((1u << 20) + 64) /* map_model maps files of 1 MiB and more */

static char root[64];            /* the input's folder, above the model's */
static char model_dir[96];       /* root/model */
static char real_model_dir[PATH_MAX];

static void remove_folders(void)
{
    rmdir(model_dir);
    rmdir(root);
}

static int make_folders(void)
{
    if (root[0]) return 1;
    snprintf(root, sizeof root, "/tmp/crowdbake-fuzz-gltf-XXXXXX");
    if (!mkdtemp(root)) return root[0] = 0, 0;
    snprintf(model_dir, sizeof model_dir, "%s/model", root);
    if (mkdir(model_dir, 0700) != 0 || !realpath(model_dir, real_model_dir)) return 0;
    atexit(remove_folders);
    return 1;
}

static int write_file(const char *path, const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    int ok = fwrite(data, 1, size, f) == size;
    return fclose(f) == 0 && ok;
}

/* A file name from the input: letters, digits, '.', '_' and '-', optionally after "../". */
static int file_path(const uint8_t *name, size_t n, char *path, size_t size)
{
    int outside = n > 3 && memcmp(name, "../", 3) == 0;
    if (outside) name += 3, n -= 3;
    if (n == 0 || n > 64 || name[0] == '.') return 0;
    for (size_t i = 0; i < n; ++i)
        if (!(name[i] >= 'a' && name[i] <= 'z') && !(name[i] >= 'A' && name[i] <= 'Z') && !(name[i] >= '0' && name[i] <= '9') &&
            name[i] != '.' && name[i] != '_' && name[i] != '-')
            return 0;
    snprintf(path, size, "%s/%.*s", outside ? root : model_dir, (int)n, (const char *)name);
    return 1;
}

static const uint8_t *find(const uint8_t *from, const uint8_t *end, const char *needle)
{
    size_t n = strlen(needle);
    for (const uint8_t *p = from; p + n <= end; ++p)
        if (*p == (uint8_t)needle[0] && memcmp(p, needle, n) == 0) return p;
    return NULL;
}

/* Writes the input's extra files; returns the model's size (the bytes before the first). */
static size_t write_extra_files(const uint8_t *data, size_t size, char paths[MAX_FILES][PATH_MAX], int *count)
{
    const uint8_t *end = data + size, *at = find(data, end, FILE_MARKER);
    size_t model_size = at ? (size_t)(at - data) : size;
    *count = 0;
    while (at && *count < MAX_FILES) {
        const uint8_t *name = at + strlen(FILE_MARKER), *eol = memchr(name, '\n', (size_t)(end - name));
        if (!eol) break;
        const uint8_t *next = find(eol + 1, end, FILE_MARKER), *stop = next ? next : end;
        if (file_path(name, (size_t)(eol - name), paths[*count], PATH_MAX) &&
            write_file(paths[*count], eol + 1, (size_t)(stop - eol - 1)))
            ++*count;
        at = next;
    }
    return model_size;
}

static uint32_t le32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}

/* The model padded to MAPPED_SIZE bytes, the same model to a reader: a GLB whose chunks end at
 * its end gets its last BIN chunk grown with zeros (or a BIN chunk appended), anything else
 * trailing spaces. NULL when it is that big already. */
static uint8_t *padded(const uint8_t *data, size_t size)
{
    if (size >= MAPPED_SIZE) return NULL;
    uint8_t *out = malloc(MAPPED_SIZE);
    if (!out) return NULL;
    memcpy(out, data, size);
    int glb = size >= 12 && memcmp(data, "glTF", 4) == 0 && le32(data + 8) == size;
    size_t last = 0, at = 12;
    while (glb && at + 8 <= size && le32(data + at) <= size - at - 8) last = at, at += 8 + (size_t)le32(data + at);
    if (!glb || at != size) {
        memset(out + size, ' ', MAPPED_SIZE - size);
        return out;
    }
    memset(out + size, 0, MAPPED_SIZE - size);
    if (last && le32(data + last + 4) == 0x004E4942u) { /* grow the BIN chunk */
        put32(out + last, (uint32_t)(MAPPED_SIZE - last - 8));
    } else { /* append one */
        put32(out + size, (uint32_t)(MAPPED_SIZE - size - 8));
        put32(out + size + 4, 0x004E4942u);
    }
    put32(out + 8, MAPPED_SIZE);
    return out;
}

/* Every file the model read lies inside its folder. */
static void check_files_inside(const cb_model *m)
{
    size_t n = strlen(real_model_dir);
    for (uint32_t i = 0; i < m->external_file_count; ++i) {
        char real[PATH_MAX];
        if (!realpath(m->external_files[i], real) || strncmp(real, real_model_dir, n) != 0 || real[n] != '/') {
            fprintf(stderr, "fuzz_gltf: the model loaded %s, outside its folder %s\n", m->external_files[i], real_model_dir);
            abort();
        }
    }
}

static void bake_some(const cb_model *m, const cb_limits *limits)
{
    cb_error err = {0};
    for (uint32_t s = 0; s < m->skin_count && s < 2; ++s) {
        cb_sampler *sampler = cb_sampler_create(m, (int32_t)s, &err);
        if (!sampler) break;
        cb_bake_options o = cb_default_bake_options();
        o.fps = 8;
        o.limits = *limits;
        o.max_texture_size = 1024;
        uint64_t work = cb_model_skin_vertex_count(m, (int32_t)s) * 64;
        cb_palette p;
        if (work < (1u << 20) && cb_palette_bake(sampler, &o, NULL, 0, &p, &err) == CB_OK) cb_palette_free(&p);
        cb_sampler_free(sampler);
        err.status = CB_OK;
    }
}

static void load_and_bake(const char *path, const cb_limits *limits)
{
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, limits, &err);
#ifdef FUZZ_DEBUG
    fprintf(stderr, "%s: %s\n", path, m ? "loaded" : err.message);
#endif
    if (!m) return;
    check_files_inside(m);
    bake_some(m, limits);
    cb_model_free(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!make_folders()) return 0;
    cb_limits limits = cb_default_limits();
    limits.max_accessor_count = 1u << 16; /* keep each run small; the checks are the same */
    limits.max_joints = 256;
    limits.max_frames = 2048;
    limits.max_file_bytes = 1u << 24;
    char extra[MAX_FILES][PATH_MAX], model[PATH_MAX];
    int files;
    size_t model_size = write_extra_files(data, size, extra, &files);
    size_t i = 0;
    while (i < model_size && (data[i] == ' ' || data[i] == '\n' || data[i] == '\r' || data[i] == '\t')) ++i;
    snprintf(model, sizeof model, "%s/%s", model_dir, i < model_size && data[i] == '{' ? "model.gltf" : "model.glb");
    if (write_file(model, data, model_size)) load_and_bake(model, &limits);
    uint8_t *big = padded(data, model_size);
    if (big && write_file(model, big, MAPPED_SIZE)) load_and_bake(model, &limits);
    free(big);
    unlink(model);
    for (int k = 0; k < files; ++k) unlink(extra[k]);
    return 0;
}
