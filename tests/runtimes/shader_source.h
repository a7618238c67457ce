/* shader_source.h - the shipped shaders' source as the GPU tests use it (GLSL on Mesa, HLSL on
 * lavapipe): the defines that pick a palette's layout and precision, and one line broken on
 * purpose to show a test catches it. Header-only, like testutil.h. */
#ifndef CROWDBAKE_TEST_SHADER_SOURCE_H
#define CROWDBAKE_TEST_SHADER_SOURCE_H

#include "testutil.h"

static const char *const layout_define[] = {"CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS"};
static const char *const precision_define[] = {"CB_PRECISION_FLOAT", "CB_PRECISION_HALF", "CB_PRECISION_U16"};

/* Replaces the line containing `marker` (a "cb:" comment of the shipped shader) with `line`. */
static inline char *break_shader(const char *src, const char *marker, const char *line)
{
    const char *at = strstr(src, marker);
    assert_non_null(at);
    const char *start = at, *end = strchr(at, '\n');
    while (start > src && start[-1] != '\n') --start;
    size_t n = strlen(src) + strlen(line) + 1;
    char *out = malloc(n);
    snprintf(out, n, "%.*s%s%s", (int)(start - src), src, line, end);
    return out;
}

#endif
