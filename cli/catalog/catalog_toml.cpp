// catalog_toml.cpp - the tomlplusplus adapter: TOML in, a validated cb_catalog out. Every
// error names the file, line and column, and for unknown keys suggests the nearest known one.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <strings.h>
#include <sys/stat.h>
#include <toml++/toml.h>
#include <vector>

#include "catalog/catalog_toml.h"
#include "catalog/catalog_canonical.h"
#include "toml_guard.h"
#include "internal/plumbing.h"
#include "internal/bake_words.h"

namespace {

struct Failure {}; // unwinds to the entry point once the error is recorded

struct Parser {
    cb_catalog *cat;
    cb_error *err;
    std::string file;
    const char *files_of = nullptr; /* whose files must exist: NULL every animal's (cb_catalog_load_checking) */

    bool checks_files(const std::string &name) const { return !files_of || name == files_of; }

    /* status: CB_ERR_IO where a file the catalog names cannot be read, as for a model on the command line. */
    [[noreturn]] void fail(const toml::source_region &where, const std::string &what, cb_status status = CB_ERR_INPUT)
    {
        cb_fail(err, status, "%s:%u:%u: %s", file.c_str(), (unsigned)where.begin.line, (unsigned)where.begin.column,
                what.c_str());
        throw Failure{};
    }

    const char *dup(const std::string &s)
    {
        const char *p = cb_arena_strdup(cat->arena, s.c_str());
        if (!p) throw std::bad_alloc();
        return p;
    }

    template <typename T> T *alloc(size_t n)
    {
        T *p = static_cast<T *>(cb_arena_alloc(cat->arena, n ? n : 1, sizeof(T)));
        if (!p) throw std::bad_alloc();
        return p;
    }

    static cb_source_pos pos(const toml::node &n)
    {
        return cb_source_pos{(uint32_t)n.source().begin.line, (uint32_t)n.source().begin.column};
    }

    static size_t distance(const std::string &a, const std::string &b) { return cb_edit_distance(a.c_str(), b.c_str()); }

    void check_keys(const toml::table &t, const std::vector<std::string> &known, const std::string &where)
    {
        for (auto &&[k, v] : t) {
            std::string key(k.str());
            if (std::find(known.begin(), known.end(), key) != known.end()) continue;
            std::string best;
            size_t best_d = 3;
            for (const std::string &c : known)
                if (distance(key, c) < best_d) best_d = distance(key, c), best = c;
            std::string msg = where + " unknown key '" + key + "'";
            msg += best.empty() ? "; known keys: " : "; did you mean '" + best + "'?";
            if (best.empty())
                for (size_t i = 0; i < known.size(); ++i) msg += (i ? ", " : "") + known[i];
            fail(k.source(), msg);
        }
    }

    std::string str(const toml::node &n, const std::string &what)
    {
        if (!n.is_string()) fail(n.source(), what + " must be a string, got " + type_name(n));
        return *n.value<std::string>();
    }

    double number(const toml::node &n, const std::string &what)
    {
        if (!n.is_number()) fail(n.source(), what + " must be a number, got " + type_name(n));
        return *n.value<double>();
    }

    int64_t integer(const toml::node &n, const std::string &what)
    {
        if (!n.is_integer()) fail(n.source(), what + " must be an integer, got " + type_name(n));
        return *n.value<int64_t>();
    }

    bool boolean(const toml::node &n, const std::string &what)
    {
        if (!n.is_boolean()) fail(n.source(), what + " must be true or false, got " + type_name(n));
        return *n.value<bool>();
    }

    static std::string type_name(const toml::node &n)
    {
        switch (n.type()) {
        case toml::node_type::string: return "a string";
        case toml::node_type::integer: return "an integer";
        case toml::node_type::floating_point: return "a number";
        case toml::node_type::boolean: return "a boolean";
        case toml::node_type::array: return "an array";
        case toml::node_type::table: return "a table";
        default: return "a date or time";
        }
    }

    /* dir/rel with "." and "dir/.." segments folded away, so messages show real paths. */
    std::string resolve(const std::string &rel) const
    {
        std::string joined = !rel.empty() && rel[0] == '/' ? rel : std::string(cat->dir) + "/" + rel;
        std::vector<std::string> parts;
        size_t start = 0;
        while (start <= joined.size()) {
            size_t end = joined.find('/', start);
            if (end == std::string::npos) end = joined.size();
            std::string part = joined.substr(start, end - start);
            if (part == ".." && !parts.empty() && parts.back() != ".." && !parts.back().empty()) parts.pop_back();
            else if (!part.empty() && part != ".") parts.push_back(part);
            else if (part.empty() && start == 0) parts.push_back(""); /* the root of an absolute path */
            start = end + 1;
        }
        std::string out;
        for (size_t i = 0; i < parts.size(); ++i) out += (i ? "/" : "") + parts[i];
        return out.empty() ? "." : out;
    }

    /* ---- [bake] and its per-animal overrides ---- */

    static const std::vector<std::string> &bake_keys()
    {
        static const std::vector<std::string> k = {"fps", "max_error", "max_fps", "layout", "precision", "format", "out_dir",
                                                   "max_texture_size", "root_motion", "fit_rows", "measure_all",
                                                   "allow_over_budget", "plant_feet",
                                                   "row_travel", "bone_space", "timed_rows"};
        return k;
    }

    /* fps = N or "auto": 1 for "auto" (*out untouched), else 0 with *out set. */
    int fps(const toml::node &n, double *out, const std::string &what)
    {
        if (n.is_string()) {
            if (*n.value<std::string>() != "auto") fail(n.source(), what + " must be a rate in frames per second or \"auto\"");
            return 1;
        }
        *out = number(n, what);
        if (!cb_fps_valid(*out)) fail(n.source(), what + " must be between 0 and 1000");
        return 0;
    }

    double max_error(const toml::node &n, const std::string &where)
    {
        double v = number(n, where + " max_error");
        if (!(v > 0)) fail(n.source(), where + " max_error must be a positive error in mm per metre of model height");
        return v;
    }

    /* `from`: the layer these keys are ([bake] or an animal's), recorded with each value. */
    void bake_settings(const toml::table &t, cb_bake_settings *b, const std::string &where, cb_setting_from from)
    {
        if (auto *n = t.get("fps")) {
            int automatic = fps(*n, &b->fps, where + " fps");
            b->fps_auto = automatic;
            b->from.fps = from;
        }
        if (auto *n = t.get("max_error"))
            b->max_error_mm = max_error(*n, where), b->max_error_given = true, b->from.max_error = from;
        if (auto *n = t.get("max_fps")) {
            b->from.max_fps = from;
            b->max_fps = number(*n, where + " max_fps");
            if (!cb_max_fps_valid(b->max_fps)) fail(n->source(), where + " max_fps must be between 2 and 1000");
        }
        if (auto *n = t.get("layout")) {
            if (!cb_layout_parse(str(*n, where + " layout").c_str(), &b->layout))
                fail(n->source(), where + " layout must be \"mat4\", \"affine\" or \"qpos\"");
            b->layout_set = true;
        }
        if (auto *n = t.get("precision")) {
            if (!cb_precision_parse(str(*n, where + " precision").c_str(), &b->precision))
                fail(n->source(), where + " precision must be \"float\", \"half\" or \"u16\"");
            b->precision_set = true;
        }
        if (auto *n = t.get("format")) {
            std::string f = str(*n, where + " format");
            b->formats = cb_formats_parse(f.c_str());
            if (!cb_catalog_formats_valid(b->formats))
                fail(n->source(), where + " format must be \"pal\", \"exr\", \"ktx2\" or \"both\", or several of them "
                                          "(\"pal,ktx2\"), with \"babylon\" beside any if wanted (\"pal,babylon\")");
        }
        if (auto *n = t.get("out_dir")) b->out_dir = dup(resolve(str(*n, where + " out_dir")));
        if (auto *n = t.get("max_texture_size")) {
            int64_t v = integer(*n, where + " max_texture_size");
            if (v < 1 || v > 65536) fail(n->source(), where + " max_texture_size must be 1..65536");
            b->max_texture_size = (uint32_t)v;
        }
        if (auto *n = t.get("root_motion")) {
            if (!cb_root_motion_parse(str(*n, where + " root_motion").c_str(), &b->root_motion))
                fail(n->source(), where + " root_motion must be \"keep\", \"in-place\" or \"loops-in-place\"");
            b->from.root_motion = from;
        }
        if (auto *n = t.get("fit_rows")) b->fit_rows = boolean(*n, where + " fit_rows"), b->from.fit_rows = from;
        if (auto *n = t.get("measure_all")) b->measure_all = boolean(*n, where + " measure_all");
        if (auto *n = t.get("row_travel")) b->row_travel_off = !boolean(*n, where + " row_travel");
        if (auto *n = t.get("bone_space")) {
            if (!cb_bone_space_parse(str(*n, where + " bone_space").c_str(), &b->bone_space))
                fail(n->source(), where + " bone_space must be \"global\" or \"local\"");
            b->bone_space_set = true;
        }
        if (auto *n = t.get("timed_rows"))
            if (!cb_timed_rows_parse(str(*n, where + " timed_rows").c_str(), &b->timed_rows))
                fail(n->source(), where + " timed_rows must be \"auto\", \"on\" or \"off\"");
        if (auto *n = t.get("allow_over_budget")) b->allow_over_budget = boolean(*n, where + " allow_over_budget");
        if (auto *n = t.get("plant_feet")) b->plant_feet = boolean(*n, where + " plant_feet");
        /* A fixed fps is checked against a max_error given beside it: an animal's own fps is not
         * held to the max_error [bake] states for error-bounded rates, unless it states its own. */
        if (t.get("fps") && !t.get("max_error")) b->max_error_given = false;
        if (!cb_bake_settings_writable(b))
            fail(t.source(), where + " precision u16 cannot be written as EXR; use format = \"pal\" or precision half|float");
    }

    /* ---- [budget] ---- */

    static uint64_t parse_size(const std::string &s, bool *ok)
    {
        char unit[16] = "";
        double v = 0;
        *ok = std::sscanf(s.c_str(), "%lf %15s", &v, unit) >= 1 && v >= 0;
        std::string u = unit;
        double mult = u == "" || u == "B" ? 1 : u == "KiB" ? 1024.0 : u == "MiB" ? 1048576.0 : u == "GiB" ? 1073741824.0
                    : u == "KB" ? 1e3 : u == "MB" ? 1e6 : u == "GB" ? 1e9 : -1;
        if (mult < 0) *ok = false;
        return (uint64_t)std::llround(v * mult);
    }

    void budget(const toml::table &t)
    {
        check_keys(t, {"target", "vram", "crowd_share", "max_bones", "max_texture_size"}, "[budget]");
        cb_budget *b = &cat->budget;
        b->set = true;
        b->pos = pos(t);
        b->crowd_share = 1.0;
        b->max_bones = 256;
        if (auto *n = t.get("target")) b->target = dup(str(*n, "[budget] target"));
        if (auto *n = t.get("vram")) {
            bool ok = true;
            if (n->is_integer()) b->vram_bytes = (uint64_t)std::max<int64_t>(0, *n->value<int64_t>());
            else b->vram_bytes = parse_size(str(*n, "[budget] vram"), &ok);
            if (!ok || b->vram_bytes == 0)
                fail(n->source(), "[budget] vram must be a size such as \"1 GiB\", \"512 MiB\" or a byte count");
        }
        if (auto *n = t.get("crowd_share")) {
            b->crowd_share = number(*n, "[budget] crowd_share");
            if (!(b->crowd_share > 0 && b->crowd_share <= 1)) fail(n->source(), "[budget] crowd_share must be in (0, 1]");
        }
        if (auto *n = t.get("max_bones")) {
            int64_t v = integer(*n, "[budget] max_bones");
            if (v < 1 || v > 65535) fail(n->source(), "[budget] max_bones must be 1..65535");
            b->max_bones = (uint32_t)v;
        }
        if (auto *n = t.get("max_texture_size")) {
            int64_t v = integer(*n, "[budget] max_texture_size");
            if (v < 1 || v > 65536) fail(n->source(), "[budget] max_texture_size must be 1..65536");
            b->max_texture_size = (uint32_t)v;
        }
        if (!b->target && !b->vram_bytes) fail(t.source(), "[budget] needs a target or a vram size");
    }

    /* ---- [animal.NAME] ---- */

    // clips or extra_clips (`key`): names or tables, into *out.
    cb_catalog_clip *clips(const toml::node &node, const char *key, uint32_t *count, const std::string &where)
    {
        if (!node.is_array()) fail(node.source(), where + " " + key + " must be a list");
        const toml::array &a = *node.as_array();
        *count = (uint32_t)a.size();
        cb_catalog_clip *out = alloc<cb_catalog_clip>(a.size());
        for (size_t i = 0; i < a.size(); ++i) {
            const toml::node &n = *a.get(i);
            cb_catalog_clip *c = &out[i];
            c->loop = -1;
            c->fps_auto = -1;
            c->pos = pos(n);
            if (n.is_string()) {
                c->source = c->name = dup(*n.value<std::string>());
                continue;
            }
            if (!n.is_table()) fail(n.source(), where + " " + key + " entries are clip names or { source = \"...\", name = \"...\" }");
            const toml::table &t = *n.as_table();
            check_keys(t, {"source", "name", "loop", "fps", "max_error"}, where + " clip");
            const toml::node *src = t.get("source");
            if (!src) fail(n.source(), where + " clip entry needs source = \"<clip name in the model>\"");
            c->source = dup(str(*src, where + " clip source"));
            c->name = t.get("name") ? dup(str(*t.get("name"), where + " clip name")) : c->source;
            if (auto *l = t.get("loop")) c->loop = boolean(*l, where + " clip loop") ? 1 : 0;
            if (auto *f = t.get("fps")) c->fps_auto = fps(*f, &c->fps, where + " clip fps");
            if (auto *e = t.get("max_error")) c->max_error_mm = max_error(*e, where + " clip");
            for (size_t k = 0; k < i; ++k)
                if (std::strcmp(out[k].name, c->name) == 0)
                    fail(n.source(), where + " two clips are named '" + c->name + "'; rename one with name = \"...\"");
        }
        return out;
    }

    // A state's keywords: "word", ["word", ...], or { keywords = [...], sync = "speed" | "time" }.
    void state(const toml::node &v, cb_catalog_state *s, const std::string &where)
    {
        std::string what = where + " state '" + s->name + "'";
        const toml::node *words_node = &v;
        if (const toml::table *t = v.as_table()) {
            check_keys(*t, {"keywords", "sync"}, what);
            words_node = t->get("keywords");
            if (!words_node) fail(v.source(), what + " needs keywords = [\"clip keyword\", ...]");
            if (const toml::node *sync = t->get("sync")) {
                std::string mode = str(*sync, what + " sync");
                if (mode != "speed" && mode != "time" && mode != "auto")
                    fail(sync->source(), what + " sync must be \"speed\" (follows the instance's speed), \"time\" (its "
                                                "own rate) or \"auto\" (decided from its words and feet)");
                s->sync = mode == "speed" ? CB_SYNC_SPEED : mode == "time" ? CB_SYNC_TIME : CB_SYNC_AUTO;
            }
        }
        std::vector<std::string> words;
        if (words_node->is_string()) words.push_back(*words_node->value<std::string>());
        else if (words_node->is_array())
            for (const toml::node &w : *words_node->as_array()) words.push_back(str(w, what + " keyword"));
        else fail(words_node->source(), what + " must be a keyword, a list of keywords or { keywords = [...], sync = ... }");
        if (words.empty()) fail(words_node->source(), what + " needs at least one clip keyword");
        s->keyword_count = (uint32_t)words.size();
        s->keywords = alloc<const char *>(words.size());
        for (size_t w = 0; w < words.size(); ++w) s->keywords[w] = dup(words[w]);
    }

    // States in the order the file writes them: toml++ keeps a table's keys sorted, so they are
    // put back in order by where each key stands (the first written is the default state).
    void states(const toml::table &t, cb_catalog_animal *an, const std::string &where)
    {
        std::vector<std::pair<const toml::key *, const toml::node *>> written;
        for (auto &&[k, v] : t) written.emplace_back(&k, &v);
        std::stable_sort(written.begin(), written.end(), [](const auto &a, const auto &b) {
            const toml::source_position &x = a.first->source().begin, &y = b.first->source().begin;
            return x.line != y.line ? x.line < y.line : x.column < y.column;
        });
        an->state_count = (uint32_t)written.size();
        an->states = alloc<cb_catalog_state>(written.size());
        for (size_t i = 0; i < written.size(); ++i) {
            cb_catalog_state *s = &an->states[i];
            s->name = dup(std::string(written[i].first->str()));
            s->pos = pos(*written[i].second);
            state(*written[i].second, s, where);
        }
    }

    // lod_max_influences = [2, 1]: what `crowdbake mesh --lod N` keeps per vertex for LOD N.
    void lod_influences(const toml::node &l, cb_catalog_animal *an, const std::string &where)
    {
        const toml::array *a = l.as_array();
        if (!a || a->size() != an->lod_count)
            fail(l.source(), where + " lod_max_influences must be a list of " + std::to_string(an->lod_count) +
                                 " numbers (1, 2 or 4), one per LOD in lods");
        an->lod_max_influences = alloc<uint32_t>(a->size());
        for (size_t i = 0; i < a->size(); ++i) {
            auto v = a->get(i)->value<int64_t>();
            if (!v || (*v != 1 && *v != 2 && *v != 4))
                fail(a->get(i)->source(), where + " lod_max_influences: each LOD keeps 1, 2 or 4 influences per vertex");
            an->lod_max_influences[i] = (uint32_t)*v;
        }
    }

    void animal(const std::string &name, const toml::table &t, const toml::key &key, cb_catalog_animal *an)
    {
        std::string where = "[animal." + name + "]";
        std::vector<std::string> known = {"model", "lods", "lod_max_influences", "clips", "extra_clips", "states",
                                         "default_state", "speed_reference"};
        known.insert(known.end(), bake_keys().begin(), bake_keys().end());
        check_keys(t, known, where);
        an->name = dup(name);
        an->pos = cb_source_pos{(uint32_t)key.source().begin.line, (uint32_t)key.source().begin.column};
        an->bake = cat->defaults;
        bake_settings(t, &an->bake, where, CB_FROM_ANIMAL);
        const toml::node *model = t.get("model");
        if (!model) fail(key.source(), where + " needs model = \"path/to/model.glb\" (relative to the catalog)");
        std::string path = resolve(str(*model, where + " model"));
        struct stat st;
        if (checks_files(name) && (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)))
            fail(model->source(), where + " model file " + path + " does not exist (paths are relative to the catalog)",
                 CB_ERR_IO);
        an->model = dup(path);
        an->model_pos = pos(*model);
        if (auto *l = t.get("lods")) {
            if (!l->is_array()) fail(l->source(), where + " lods must be a list of model paths");
            const toml::array &a = *l->as_array();
            an->lod_count = (uint32_t)a.size();
            an->lods = alloc<const char *>(a.size());
            an->lod_pos = alloc<cb_source_pos>(a.size());
            for (size_t i = 0; i < a.size(); ++i) {
                std::string lp = resolve(str(*a.get(i), where + " lod"));
                if (checks_files(name) && stat(lp.c_str(), &st) != 0)
                    fail(a.get(i)->source(), where + " LOD file " + lp + " does not exist", CB_ERR_IO);
                an->lods[i] = dup(lp);
                an->lod_pos[i] = pos(*a.get(i));
            }
        }
        if (auto *l = t.get("lod_max_influences")) lod_influences(*l, an, where);
        if (auto *c = t.get("clips")) an->clips = clips(*c, "clips", &an->clip_count, where);
        if (auto *c = t.get("extra_clips")) {
            if (an->clips)
                fail(c->source(), where + " clips lists every clip baked: move extra_clips into it, or drop clips "
                                          "(then the states' clips and extra_clips are baked)");
            an->extra_clips = clips(*c, "extra_clips", &an->extra_clip_count, where);
        }
        if (auto *s = t.get("states")) {
            if (!s->is_table()) fail(s->source(), where + " states must be a table: state = [\"keyword\", ...]");
            states(*s->as_table(), an, where);
        }
        if (auto *d = t.get("default_state")) {
            an->default_state = dup(str(*d, where + " default_state"));
            an->default_state_from = "the catalog's default_state";
            bool found = false;
            std::string list;
            for (uint32_t i = 0; i < an->state_count; ++i) {
                found |= std::strcmp(an->states[i].name, an->default_state) == 0;
                list += std::string(i ? ", " : "") + an->states[i].name;
            }
            if (!found)
                fail(d->source(), where + " default_state '" + an->default_state + "' is not one of its states (" +
                                      (list.empty() ? "none defined" : list) + ")");
        } else if (an->state_count) {
            char why[512];
            an->default_state = an->states[cb_pick_default_state(an, why, sizeof why)].name;
            an->default_state_from = dup(why);
        }
        an->speed_auto = true;
        if (auto *sp = t.get("speed_reference")) {
            an->speed_pos = pos(*sp);
            if (sp->is_string()) {
                std::string v = *sp->value<std::string>();
                bool state = false;
                for (uint32_t i = 0; i < an->state_count; ++i) state |= v == an->states[i].name;
                if (v != "auto" && !state)
                    fail(sp->source(), where + " speed_reference must be a speed in model units/s, \"auto\" or the name of a state");
                if (state) an->speed_state = dup(v);
            } else {
                an->speed_reference = number(*sp, where + " speed_reference");
                if (!(an->speed_reference > 0)) fail(sp->source(), where + " speed_reference must be positive");
                an->speed_auto = false;
            }
        }
    }

    void catalog(const toml::table &root)
    {
        check_keys(root, {"bake", "budget", "animal"}, "catalog:");
        cb_bake_settings &d = cat->defaults;
        d = cb_default_bake_settings();
        d.out_dir = dup(resolve("build/roster"));
        if (auto *b = root.get("bake")) {
            if (!b->is_table()) fail(b->source(), "[bake] must be a table");
            check_keys(*b->as_table(), bake_keys(), "[bake]");
            bake_settings(*b->as_table(), &d, "[bake]", CB_FROM_CATALOG);
        }
        if (auto *b = root.get("budget")) {
            if (!b->is_table()) fail(b->source(), "[budget] must be a table");
            budget(*b->as_table());
        }
        const toml::node *animals = root.get("animal");
        if (!animals || !animals->is_table() || animals->as_table()->empty())
            fail(animals ? animals->source() : root.source(), "the catalog lists no animals; add [animal.NAME] tables");
        const toml::table &at = *animals->as_table();
        std::vector<std::pair<std::string, const toml::key *>> names;
        for (auto &&[k, v] : at) {
            std::string n(k.str());
            if (!v.is_table()) fail(v.source(), "[animal." + n + "] must be a table");
            if (n.empty() || n.find_first_of("/\\\0", 0, 3) != std::string::npos || n[0] == '.')
                fail(k.source(), "animal name '" + n + "' cannot name a file; use letters, digits, '-' and '_'");
            for (auto &[other, ok] : names)
                if (strcasecmp(other.c_str(), n.c_str()) == 0)
                    fail(k.source(), "animal '" + n + "' and '" + other + "' differ only in case; their files would collide");
            names.push_back({n, &k});
        }
        std::sort(names.begin(), names.end());
        cat->animal_count = (uint32_t)names.size();
        cat->animals = alloc<cb_catalog_animal>(names.size());
        for (size_t i = 0; i < names.size(); ++i) {
            animal(names[i].first, *at.get(names[i].first)->as_table(), *names[i].second, &cat->animals[i]);
            cat->animals[i].canonical = dup(catalog_canonical_words(cat->dir, &cat->animals[i]));
        }
    }
};

cb_status parse(const char *text, size_t size, const char *path, const char *files_of, cb_catalog *out, cb_error *err)
{
    std::memset(out, 0, sizeof *out);
    unsigned line, column;
    if (toml_non_ascii_outside_strings(text, size, &line, &column))
        return cb_fail(err, CB_ERR_INPUT, "%s:%u:%u: a non-ASCII character outside any quoted string or comment, which "
                       "TOML does not allow; put the key or value in quotes", path, line, column);
    out->arena = cb_arena_create();
    if (!out->arena) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    Parser p{out, err, path};
    p.files_of = files_of;
    try {
        out->path = p.dup(path);
        std::string dir = path;
        size_t slash = dir.find_last_of('/');
        out->dir = p.dup(slash == std::string::npos ? "." : dir.substr(0, slash));
        toml::table root = toml::parse(std::string_view(text, size), std::string(path));
        p.catalog(root);
        return CB_OK;
    } catch (const toml::parse_error &e) {
        cb_fail(err, CB_ERR_INPUT, "%s:%u:%u: %s", path, (unsigned)e.source().begin.line, (unsigned)e.source().begin.column,
                std::string(e.description()).c_str());
    } catch (const Failure &) {
    } catch (const std::bad_alloc &) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", path);
    } catch (const std::exception &e) {
        cb_fail(err, CB_ERR_INPUT, "%s: %s", path, e.what());
    }
    cb_catalog_free(out);
    return err->status;
}

} // namespace

extern "C" cb_status cb_catalog_parse(const char *text, size_t size, const char *path, cb_catalog *out, cb_error *err)
{
    return parse(text, size, path, NULL, out, err);
}

extern "C" cb_status cb_catalog_load(const char *path, cb_catalog *out, cb_error *err)
{
    return cb_catalog_load_checking(path, NULL, out, err);
}

extern "C" cb_status cb_catalog_load_checking(const char *path, const char *files_of, cb_catalog *out, cb_error *err)
{
    std::memset(out, 0, sizeof *out);
    FILE *f = std::fopen(path, "rb");
    if (!f) return cb_fail(err, CB_ERR_IO, "%s: cannot read: %s", path, std::strerror(errno));
    std::string text;
    char buf[65536];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
        text.append(buf, n);
        if (text.size() > (64u << 20)) {
            std::fclose(f);
            return cb_fail(err, CB_ERR_INPUT, "%s: larger than 64 MiB; not a catalog", path);
        }
    }
    int failed = std::ferror(f) ? errno : 0; /* a directory opens, then reads nothing: not an empty catalog */
    std::fclose(f);
    if (failed) return cb_fail(err, CB_ERR_IO, "%s: cannot read: %s", path, std::strerror(failed));
    return parse(text.data(), text.size(), path, files_of, out, err);
}
