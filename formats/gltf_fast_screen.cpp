// gltf_fast_screen.cpp - what the fast path of the glTF load (gltf_fast.cpp) checks before it
// parses: that the file is a GLB whose chunks tinygltf takes, and that every number in its JSON
// reads as RapidJSON reads it. A file that fails either goes to the tinygltf path.
#include <algorithm>
#include <cstring>

#include "gltf_parts.h"

namespace cbgltf {

// ---- numbers RapidJSON's full precision reads as simdjson does ----
//
// tinygltf reads numbers with RapidJSON's full precision, which is not correctly rounded
// everywhere: a zero whose exponent, less its fraction's digits, is past +-22 leaves its exact
// path and reads as whatever lies in its buffer ("0e56" gave 1.27e30 once, "0.0e-22"
// -1.75e-192), more than 17 significant digits near a halfway point and subnormals may be an
// ulp off, and it refuses a zero past 1e308 ("0e400") that simdjson takes.
// simdjson rounds all of them correctly, so a file with such a number goes to tinygltf. What
// both read alike, checked against RapidJSON 1.1.0 on millions of numbers (random, shortest
// and %.15g to %.17g forms of doubles, and cuts of halfway points): a nonzero number of at
// most 17 significant digits from 1e-291 to 1e290, or a zero within the exponent range
// above. Integers need no screen: both read them exactly, and simdjson refuses those past 64
// bits (RapidJSON's doubles).

static constexpr bool is_digit(unsigned char c) { return (unsigned char)(c - '0') < 10; }

// The number whose first digit is at s[i], read as JSON's grammar reads it (a screened
// match inside a string reads as whatever digits it has). *end: the byte after it.
static bool number_read_alike(const char *s, size_t n, size_t i, size_t *end)
{
    size_t int_digits = 0, frac_digits = 0, significant = 0;
    bool any_nonzero = false;
    auto digit = [&](char c) {
        any_nonzero |= c != '0';
        significant += any_nonzero;
    };
    for (; i < n && is_digit((unsigned char)s[i]); ++i, ++int_digits) digit(s[i]);
    if (i + 1 < n && s[i] == '.' && is_digit((unsigned char)s[i + 1]))
        for (++i; i < n && is_digit((unsigned char)s[i]); ++i, ++frac_digits) digit(s[i]);
    long exponent = 0;
    bool has_exponent = i + 1 < n && (s[i] | 0x20) == 'e';
    if (has_exponent) {
        size_t at = i + 1;
        bool minus = at < n && s[at] == '-';
        at += at < n && (s[at] == '-' || s[at] == '+');
        if (at < n && is_digit((unsigned char)s[at])) {
            for (i = at; i < n && is_digit((unsigned char)s[i]); ++i)
                if (exponent < 100000) exponent = exponent * 10 + (s[i] - '0'); // past it: out of range anyway
            if (minus) exponent = -exponent;
        } else {
            has_exponent = false;
        }
    }
    *end = i;
    if (int_digits == 0 || (frac_digits == 0 && !has_exponent)) return true; // no digits, or an integer
    long scale = exponent - (long)frac_digits; // the value: the digits times 10^scale
    if (!any_nonzero) return scale >= -22 && scale <= 22;
    long magnitude = scale + (long)significant; // the value is below 10^magnitude, at least 10^(magnitude - 1)
    return significant <= 17 && magnitude >= -290 && magnitude <= 290;
}

// Whether the 256 bytes from b (and b[-1]) may hold a number with a fraction or an exponent: a
// '.' or a digit before an 'e' or 'E'. A loop without branches that the compiler vectorizes, as
// in mentions(); most of a rig's numbers are integers, and most blocks hold neither.
static bool may_hold_double(const char *b)
{
    unsigned char hit = 0;
    for (int k = 0; k < 256; ++k) {
        unsigned char c = (unsigned char)b[k], before = (unsigned char)b[k - 1];
        hit |= (c == '.') | (((c | 0x20) == 'e') & is_digit(before));
    }
    return hit;
}

// Whether every number with a fraction or an exponent in the JSON reads alike: the blocks that
// may hold one are read number by number.
bool doubles_read_alike(const char *s, size_t n)
{
    size_t read_to = 0; // the numbers before here are read
    for (size_t at = 1; at < n; at += 256) {
        size_t stop = std::min(n, at + 256);
        if (stop == at + 256 && !may_hold_double(s + at)) continue;
        for (size_t k = std::max(at, read_to); k < stop; ++k) {
            if (s[k] != '.' && ((s[k] | 0x20) != 'e' || !is_digit((unsigned char)s[k - 1]))) continue;
            size_t first = k;
            while (first > 0 && (is_digit((unsigned char)s[first - 1]) || s[first - 1] == '.')) --first;
            if (!number_read_alike(s, n, first, &read_to)) return false;
            k = std::max(k, read_to - 1);
        }
    }
    return true;
}

// A GLB that tinygltf takes: a JSON chunk (4-byte aligned) and at most a BIN chunk, as
// LoadBinaryFromMemory checks them.
bool glb_chunks(const unsigned char *data, size_t size, size_t *json_length, size_t *bin_at, size_t *bin_length)
{
    if (size < 20 || std::memcmp(data, "glTF", 4) != 0) return false;
    uint64_t length = le32(data + 8), json_end = 20ull + le32(data + 12);
    if (le32(data + 4) != 2 || length > size || json_end > length || le32(data + 12) < 4 || json_end % 4 || le32(data + 16) != 0x4E4F534Au)
        return false;
    *json_length = le32(data + 12);
    *bin_at = 0, *bin_length = 0;
    if (json_end == length) return true;
    if (json_end + 12 > length) return false;
    uint64_t chunk = le32(data + json_end);
    if (chunk < 4 || chunk % 4 || json_end + chunk > length || le32(data + json_end + 4) != 0x004E4942u) return false;
    *bin_at = (size_t)json_end + 8, *bin_length = (size_t)chunk;
    return true;
}

} // namespace cbgltf
