#!/bin/sh
# bundle.sh BUNDLE - copies into BUNDLE/lib every shared library BUNDLE/bin/crowdbake needs,
# directly or through another, except glibc's own (the C library, its loader and the libraries
# it ships: libm, libpthread, libdl, librt), which every Linux root has. The command finds them
# through its run path, $ORIGIN/../lib (make bundle links it so).
set -eu
bundle=$1
lib=$bundle/lib
rm -rf "$lib"
mkdir -p "$lib"
# ldd lists the whole closure: "name => /path (address)".
ldd "$bundle/bin/crowdbake" | awk '$2 == "=>" && $3 ~ /^\// { print $1, $3 }' | while read -r name path; do
    case $name in
    ld-linux*|libc.so.*|libm.so.*|libpthread.so.*|libdl.so.*|librt.so.*) ;;
    *) cp -L "$path" "$lib/$name" ;;
    esac
done
# Anything left resolved outside the bundle, apart from glibc, is a mistake worth stopping for.
libdir=$(cd "$lib" && pwd -P)
outside=$(env -u LD_LIBRARY_PATH ldd "$bundle/bin/crowdbake" | awk '$2 == "=>" { print $1, $3 }' |
          grep -v "^\(ld-linux\|libc\.so\|libm\.so\|libpthread\.so\|libdl\.so\|librt\.so\)" |
          while read -r name path; do
              case $(realpath "$path" 2>/dev/null) in "$libdir"/*) ;; *) echo "$name => $path" ;; esac
          done)
if [ -n "$outside" ]; then
    echo "bundle.sh: these libraries resolve outside $lib: $outside" >&2
    exit 1
fi
echo "crowdbake: $bundle: bin/crowdbake and $(ls "$lib" | wc -l) libraries ($(du -sh "$bundle" | cut -f1))"
