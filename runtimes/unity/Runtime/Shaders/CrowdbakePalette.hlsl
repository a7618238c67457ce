// CrowdbakePalette.hlsl - the shared HLSL runtime, runtimes/hlsl/crowdbake_palette.hlsl, reached from
// the repository's checkout (a Unity project that names this package by path: "file:.../runtimes/unity").
// `make unity-package` replaces this file with that one in the packed package, which then stands alone.
#include "../../../hlsl/crowdbake_palette.hlsl"
