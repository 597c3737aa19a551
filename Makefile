# clwhitted — an OpenCL Whitted ray tracer with a C99 host.
#   make          build build/clwhitted
#   make render   install the missing build and run-time packages, build, render the
#                 default scene
#   make test     install the missing test and development packages, build and run the
#                 whole test suite (on PoCL)
#   make install  install clwhitted, clwhitted-imgtool and the man page (PREFIX, BINDIR,
#                 MANDIR, DESTDIR)
#   make gallery  render build/gallery/ (the SPD scenes from SPD_DIR and the default scene);
#                 UPDATE_DOCS=1 also copies it over docs/gallery/
#   make bench    clwhitted, the Embree anchor and POV-Ray side by side (docs/benchmarks.md)
#   make format   clang-format the C sources; make format-check checks them (CI)

CC      ?= cc
BUILD   := build
PREFIX  ?= /usr/local
BINDIR  ?= $(PREFIX)/bin
MANDIR  ?= $(PREFIX)/share/man
INSTALL ?= install
SPD_DIR ?= ../shared/scenes/spd

# Strict warnings: every host file, every test.
WARN    := -std=c99 -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes \
           -Wmissing-prototypes -Wpointer-arith -Wvla -Wformat=2 -Wundef
OPT     ?= -O2 -g
CPPFLAGS += -D_POSIX_C_SOURCE=200809L -DCL_TARGET_OPENCL_VERSION=120 \
           -Ihost -Ikernels -I$(BUILD)
# Recursively expanded on purpose: pkg-config runs only when a rule needs it, so that
# `make render` can install the packages before anything asks for them.
PKG_CFLAGS = $(shell pkg-config --cflags libpng libcjson OpenEXR assimp 2>/dev/null)
EXR_CORE   = $(or $(filter -lOpenEXRCore%,$(shell pkg-config --libs OpenEXR 2>/dev/null)),-lOpenEXRCore)
LDLIBS     = -lOpenCL $(shell pkg-config --libs libpng libcjson 2>/dev/null) $(EXR_CORE) -lz -lm -ldl -pthread \
             $(EXTRA_LIBS)
# (make asan links libstdc++ through EXTRA_LIBS: see ASAN_LIBS below)
EXTRA_LIBS ?=
# --preview: GLFW and Xlib headers only; the libraries are loaded at run time (dlopen).
GUI_CFLAGS = $(shell pkg-config --cflags glfw3 x11 2>/dev/null)
CFLAGS  += $(WARN) $(OPT) -pthread $(PKG_CFLAGS) $(GUI_CFLAGS)

# Host modules: every host/*.c but main.c goes into a static library that clwhitted, the
# tools and the tests link, so each program holds only the objects it uses.
LIB_SRC := $(filter-out host/main.c $(wildcard host/mpi_*.c),$(wildcard host/*.c))
LIB_OBJ := $(patsubst host/%.c,$(BUILD)/%.o,$(LIB_SRC)) $(BUILD)/kernels_src.o
LIB     := $(BUILD)/libclwhitted.a
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/%,$(TEST_SRC))
DEFAULT_SCENE := scenes/default.json
# Header dependencies, written by the compiler (-MMD -MP) and by tools/embed-kernels.sh.
DEPFLAGS = -MMD -MP

.PHONY: all render test clean deps deps-runtime deps-dev format format-check install uninstall \
        gallery bench bench-instances spd-counts
all: $(BUILD)/clwhitted $(BUILD)/scene2pov

$(BUILD):
	mkdir -p $(BUILD)

# The kernel program is embedded in the binary: kernels/clwhitted.cl with every local
# #include inlined, with #line markers (tools/embed-kernels.sh writes its dependencies).
$(BUILD)/kernels_src.c: kernels/clwhitted.cl tools/embed-kernels.sh | $(BUILD)
	sh tools/embed-kernels.sh kernels/clwhitted.cl $@.tmp $(BUILD)/kernels_src.d.tmp
	sed 's|$@.tmp|$@|' $(BUILD)/kernels_src.d.tmp > $(BUILD)/kernels_src.d
	rm -f $(BUILD)/kernels_src.d.tmp
	mv $@.tmp $@

$(BUILD)/kernels_src.o: $(BUILD)/kernels_src.c
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/%.o: host/%.c | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) -c $< -o $@

$(LIB): $(LIB_OBJ)
	rm -f $@
	$(AR) rcs $@ $^

$(BUILD)/clwhitted: $(BUILD)/main.o $(LIB)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

# clwhitted-mpi (docs/mpi.md): host/mpi_*.c and the library, built by mpicc (driving $(CC))
# only where mpicc is found; without MPI everything else builds as before.
MPICC    ?= mpicc
HAVE_MPI := $(if $(shell command -v $(MPICC) 2>/dev/null),1)
MPI_CC    = OMPI_CC='$(CC)' MPICH_CC='$(CC)' $(MPICC)
MPI_OBJ  := $(patsubst host/%.c,$(BUILD)/%.o,$(wildcard host/mpi_*.c))
ifeq ($(HAVE_MPI),1)
all: $(BUILD)/clwhitted-mpi
test: $(BUILD)/clwhitted-mpi
endif

$(BUILD)/mpi_%.o: host/mpi_%.c | $(BUILD)
	$(MPI_CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) -c $< -o $@

$(BUILD)/clwhitted-mpi: $(MPI_OBJ) $(LIB)
	$(MPI_CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

# Converts a scene to POV-Ray SDL with the same model (for comparisons and benchmarks).
$(BUILD)/scene2pov: tools/scene2pov.c $(LIB) | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) $< $(LIB) $(LDLIBS) -o $@

$(BUILD)/test_%: tests/test_%.c $(LIB) | $(BUILD) deps-dev
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $(DEPFLAGS) $< $(LIB) $(LDLIBS) -lcmocka -o $@

-include $(wildcard $(BUILD)/*.d)

# tools/install-deps: --runtime for building and rendering, --dev for the rest (tests,
# sanitizers, fuzzing, benchmarks, reports); both with no option (CI). docs/testing.md
# lists them.
deps:
	sh tools/install-deps
deps-runtime:
	sh tools/install-deps --runtime
# make test installs the Debian test packages; Intel's OpenCL runtime (about 830 MB from
# PyPI, optional for the tests) only when asked: make test INSTALL_INTEL_OCL=1, or plain
# tools/install-deps (CI).
INSTALL_INTEL_OCL ?= 0
deps-dev:
	INSTALL_INTEL_OCL=$(INSTALL_INTEL_OCL) sh tools/install-deps --dev

render: deps-runtime
	$(MAKE) all
	$(BUILD)/clwhitted -o $(BUILD)/default.exr $(DEFAULT_SCENE)
	$(BUILD)/clwhitted -o $(BUILD)/default.png $(DEFAULT_SCENE)
	@echo "Rendered $(DEFAULT_SCENE): $(BUILD)/default.exr (linear) and $(BUILD)/default.png (sRGB)"

# Each test binary runs from the repository root; all of them run even if one fails. The
# test packages come first (deps-dev: an order-only prerequisite of every test binary).
test: deps-dev $(BUILD)/clwhitted $(TEST_BIN)
	@fail=0; for t in $(TEST_BIN); do \
	    echo "== $$t"; $$t || fail=1; \
	done; \
	sh tests/cli.sh $(BUILD)/clwhitted || fail=1; \
	sh tests/safety.sh $(BUILD) || fail=1; \
	sh tests/instances.sh $(BUILD) || fail=1; \
	sh tests/build.sh $(BUILD) || fail=1; \
	sh tests/install.sh || fail=1; \
	sh tests/gallery.sh $(BUILD)/clwhitted || fail=1; \
	sh tests/quality.sh $(BUILD)/clwhitted $(BUILD)/imgtool || fail=1; \
	sh tests/docs.sh $(BUILD)/clwhitted || fail=1; \
	sh tests/meshes.sh $(BUILD) || fail=1; \
	sh tests/bench.sh $(BUILD) || fail=1; \
	sh tests/mpi.sh $(BUILD) || fail=1; \
	if [ $$fail -ne 0 ]; then echo "make test: FAILED"; exit 1; fi; echo "make test: all passed"

# The installed binary needs nothing else at run time: the kernels are embedded.
# imgtool is installed as clwhitted-imgtool (pbrt-v4 installs an imgtool of its own).
install: $(BUILD)/clwhitted $(BUILD)/imgtool
	$(INSTALL) -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(MANDIR)/man1
	$(INSTALL) -m 755 $(BUILD)/clwhitted $(DESTDIR)$(BINDIR)/clwhitted
	$(INSTALL) -m 755 $(BUILD)/imgtool $(DESTDIR)$(BINDIR)/clwhitted-imgtool
	$(INSTALL) -m 644 docs/clwhitted.1 $(DESTDIR)$(MANDIR)/man1/clwhitted.1

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/clwhitted $(DESTDIR)$(BINDIR)/clwhitted-imgtool \
	    $(DESTDIR)$(MANDIR)/man1/clwhitted.1

# The seven SPD scenes at 512x512 and the default scene, with times, in build/gallery/.
# The tracked docs/gallery/ and docs/quality/ change only when asked: UPDATE_DOCS=1 copies
# the results of `make gallery` and `make quality` over them.
UPDATE_DOCS ?=
gallery: $(BUILD)/clwhitted
	SPD_DIR='$(SPD_DIR)' GALLERY_DIR='$(BUILD)/gallery' sh tools/gallery $(BUILD)/clwhitted
ifeq ($(UPDATE_DOCS),1)
	cp $(BUILD)/gallery/README.md $(BUILD)/gallery/*.png docs/gallery/
endif

FORMAT_SRC = host/*.c host/*.h kernels/*.h kernels/*.cl tests/*.c tests/*.h tests/fuzz/*.c \
             tests/fuzz/*.h tools/*.c

# ---- Benchmark (tools/bench --help; docs/benchmarks.md) -----------------------------------
# The speed anchor: a plain Embree 3 Whitted tracer of the same model, built from the shared
# folder (which may be read-only) into build/. Needs libembree-dev and libpng-dev.
SHARED_DIR    ?= ../shared
ANCHOR_DIR    ?= $(SHARED_DIR)/anchors/embree-whitted
ANCHOR_CFLAGS ?= -O2 -march=native
$(BUILD)/embree-anchor: $(wildcard $(ANCHOR_DIR)/embree_anchor.c) | $(BUILD)
	@[ -f '$(ANCHOR_DIR)/embree_anchor.c' ] || { echo "embree-anchor: \
	$(ANCHOR_DIR)/embree_anchor.c not found (set ANCHOR_DIR or SHARED_DIR)" >&2; exit 1; }
	@echo '#include <embree3/rtcore.h>' | $(CC) -E -x c - >/dev/null 2>&1 || { echo \
	"embree-anchor: libembree-dev is not installed (sh tools/install-deps)" >&2; exit 1; }
	$(CC) $(ANCHOR_CFLAGS) '$(ANCHOR_DIR)/embree_anchor.c' -o $@ -lembree3 -lpng -lpthread -lm

# clwhitted, the anchor and POV-Ray side by side: the SPD scenes at 512x512 and 2048x2048,
# per-phase fixed costs, and the scaling table over generated scenes (build/bench/gen/).
# Not part of make test (which runs tests/bench.sh, a smoke run). BENCH_ARGS passes options
# (BENCH_ARGS=--no-anchor runs without the anchor); results go to build/bench/, and with
# UPDATE_DOCS=1 also into the generated section of docs/benchmarks.md.
bench: $(BUILD)/clwhitted $(BUILD)/scene2pov $(BUILD)/imgcmp $(BUILD)/clstartup \
       $(if $(filter --no-anchor,$(BENCH_ARGS)),,$(BUILD)/embree-anchor)
	tools/bench --anchor $(BUILD)/embree-anchor $(BENCH_ARGS) \
	    $(if $(filter 1,$(UPDATE_DOCS)),--update-docs docs/benchmarks.md)
	tools/bench-instances $(BENCH_INSTANCES_ARGS)
# tests/bench.sh runs POV-Ray through scene2pov, and the anchor where its source is here.
test: $(BUILD)/scene2pov $(BUILD)/clstartup $(if $(wildcard $(ANCHOR_DIR)/embree_anchor.c),$(BUILD)/embree-anchor)

# A mesh placed many times, instanced against flattened (docs/benchmarks.md, "Instances").
bench-instances: $(BUILD)/clwhitted $(BUILD)/imgcmp
	tools/bench-instances $(BENCH_INSTANCES_ARGS)

# SPD ray counts against POV-Ray tracing the same corner rays.
spd-counts: $(BUILD)/clwhitted $(BUILD)/scene2pov
	tools/spd-counts $(SPD_COUNTS_ARGS)

format:
	clang-format -i $(FORMAT_SRC)

format-check:
	clang-format --dry-run -Werror $(FORMAT_SRC)

clean:
	rm -rf $(BUILD) build-asan build-fuzz

# ---- Portability check (tools/portability-check; docs/portability.md) ---------------------
# build/imgcmp compares images under the check's tolerance; build/cldevices lists the
# OpenCL devices with their limits; build/oclgrind-fill-shim.so works around an Oclgrind
# false positive in its uninitialised-value check.
#   make portability                       every device and scene (tools/portability-check):
#                                          PoCL, Intel's OpenCL runtime (tools/install-deps puts
#                                          it in .cache/intel-ocl), Oclgrind
#   make portability PORTABILITY_ARGS=--ci  small images (CI adds --require)
# Intel's runtime for anything else: tools/with-intel-ocl [--only] COMMAND, e.g.
#   tools/with-intel-ocl --only make test   the tests on Intel's device
PORTABILITY_TOOLS := $(BUILD)/imgcmp $(BUILD)/imgtool $(BUILD)/cldevices \
                     $(BUILD)/oclgrind-fill-shim.so
PORTABILITY_ARGS ?=

.PHONY: portability portability-tools
portability-tools: $(BUILD)/clwhitted $(PORTABILITY_TOOLS)

$(BUILD)/imgcmp: tools/imgcmp.c $(LIB) | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) $< $(LIB) $(LDLIBS) -o $@

$(BUILD)/cldevices: tools/cldevices.c $(LIB) | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) $< $(LIB) -lOpenCL -o $@

# build/clstartup: a process that only opens the OpenCL device (tools/bench's start-up floor).
$(BUILD)/clstartup: tools/clstartup.c $(LIB) | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) $< $(LIB) -lOpenCL -o $@

$(BUILD)/oclgrind-fill-shim.so: tools/oclgrind-fill-shim.c | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) -fPIC -shared $< -o $@ -ldl

# The bundle for another machine (tools/portability-bundle), made and run here on PoCL's
# pthread device against its own reference images: it must hold all that the check needs.
portability: portability-tools
	bash tools/portability-check --self-test
	bash tools/portability-check $(PORTABILITY_ARGS)
	rm -rf $(BUILD)/portability-bundle $(BUILD)/portability-bundle-run
	BUILD=$(abspath $(BUILD)) bash tools/portability-bundle --ci $(BUILD)/portability-bundle
	$(BUILD)/portability-bundle/run --devices pocl-pthread --out $(abspath $(BUILD))/portability-bundle-run

# --- Speed against error (tools/quality-report) ---
# build/imgtool: the image tool (convert, diff, info; installed as clwhitted-imgtool), and
# the report's EXR to raw float32. `make quality` runs
# the report on three SPD scenes (they live outside the repository: QUALITY_SCENES) and
# writes everything to build/quality/, with the figure and the tables of all the scenes
# (quality.png, quality.md); UPDATE_DOCS=1 also copies those two over docs/quality/.
# QUALITY_ARGS="--replot" redoes the outputs from the last run without rendering.
QUALITY_SCENES ?= ../shared/scenes/spd/tetra.nff ../shared/scenes/spd/balls.nff \
                  ../shared/scenes/spd/teapot.nff
QUALITY_ARGS   ?=
.PHONY: quality
all: $(BUILD)/imgtool
test: $(BUILD)/imgtool $(BUILD)/imgcmp

$(BUILD)/imgtool: tools/imgtool.c $(LIB) | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(DEPFLAGS) $< $(LIB) $(LDLIBS) -o $@

quality: $(BUILD)/clwhitted $(BUILD)/imgtool
	tools/quality-report --clwhitted $(BUILD)/clwhitted --imgtool $(BUILD)/imgtool \
	    -o $(BUILD)/quality --figure $(BUILD)/quality/quality.png \
	    --table $(BUILD)/quality/quality.md -W 256 -H 256 $(QUALITY_ARGS) $(QUALITY_SCENES)
ifeq ($(UPDATE_DOCS),1)
	cp $(BUILD)/quality/quality.png $(BUILD)/quality/quality.md docs/quality/
endif

# ---- Robustness: fuzzing and the sanitizer build ----------------------------------------------
#   make fuzz [FUZZ_SECONDS=60]  builds a libFuzzer target per scene reader (clang,
#       -fsanitize=fuzzer,address,undefined) into build-fuzz/ and runs each for FUZZ_SECONDS,
#       one after the other; a crash, leak, hang, huge allocation or broken error message
#       (tests/fuzz/fuzz_check.h) fails, leaving the input in build-fuzz/artifacts/TARGET/.
#       Copy it into tests/fuzz/regressions/TARGET/: build/test_fuzzcorpus replays those.
#   make asan  builds everything into build-asan/ with AddressSanitizer, LeakSanitizer and
#       UndefinedBehaviorSanitizer (no recovery) and runs the whole test suite there; leaks
#       inside the OpenCL stack are suppressed by tests/lsan.supp (third-party libraries only).
FUZZ_CC      ?= clang
FUZZ_BUILD   := build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := nff json mesh
FUZZ_CFLAGS  := -g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined \
                -fno-sanitize-recover=all
# Each target links the scene model and its one reader, nothing else (no cJSON for NFF).
FUZZ_SRC       := host/scene.c host/scene_geom.c host/scene_mesh.c host/xform.c host/scene_io.c \
                  host/sys.c
FUZZ_SRC_nff   := $(FUZZ_SRC) host/scene_nff.c host/scene_nff_lex.c
FUZZ_SRC_json  := $(FUZZ_SRC) host/scene_json.c host/scene_json_objects.c host/scene_json_value.c \
                  host/scene_json_xform.c
FUZZ_LIBS_json  = $(shell pkg-config --libs libcjson 2>/dev/null)
# The mesh reader over assimp, loaded at run time (not instrumented: its own memory errors
# show only as crashes or through the interceptors, e.g. of memcpy).
FUZZ_SRC_mesh  := $(FUZZ_SRC) host/mesh_import.c host/mesh_file.c host/mesh_material.c \
                  host/mesh_scene.c host/assimp_dl.c
FUZZ_LIBS_mesh  = -ldl
FUZZ_HEADERS   := tests/fuzz/fuzz_check.h tests/fuzz/fuzz_mesh.h host/config.h host/sys.h host/xform.h $(wildcard host/scene*.h) \
                  $(wildcard host/mesh*.h) host/assimp_dl.h
# Inputs up to 64 KiB (larger seeds, such as the SPD scenes, are cut there); 10 s per input
# is a hang; one allocation over 256 MiB or 2 GiB in all is a failure.
FUZZ_OPTS    := -max_len=65536 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=256 \
                -print_final_stats=1
# Seeds beyond tests/fuzz/corpus/TARGET: the scenes in the repository, and the SPD scenes in
# ../shared when present (CI clones have none).
FUZZ_SEEDS_nff  = scenes/spd/*.nff tests/scenes/pov/*.nff tests/scenes/parse/*.nff \
                  $(wildcard ../shared/scenes/spd/*.nff)
FUZZ_SEEDS_json = scenes/*.json tests/scenes/parse/*.json
FUZZ_SEEDS_mesh =

ASAN_CC      ?= clang
ASAN_BUILD   := build-asan
ASAN_FLAGS   := -O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined \
                -fno-sanitize-recover=all
ASAN_ENV     := ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1 \
                LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
                UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

.PHONY: fuzz fuzz-build asan
$(BUILD)/test_fuzzcorpus: tests/fuzz/fuzz_check.h tests/fuzz/fuzz_mesh.h

# The sources of target T are FUZZ_SRC_T, its libraries FUZZ_LIBS_T.
.SECONDEXPANSION:
$(FUZZ_BUILD)/fuzz_%: tests/fuzz/fuzz_%.c $$(FUZZ_SRC_$$*) $(FUZZ_HEADERS)
	@mkdir -p $(FUZZ_BUILD)
	$(FUZZ_CC) $(CPPFLAGS) $(WARN) $(FUZZ_CFLAGS) $(PKG_CFLAGS) $< $(FUZZ_SRC_$*) \
	    $(FUZZ_LIBS_$*) -lm -o $@

fuzz-build: $(FUZZ_TARGETS:%=$(FUZZ_BUILD)/fuzz_%)

fuzz: fuzz-build
	@set -e; $(foreach t,$(FUZZ_TARGETS),\
	    rm -rf $(FUZZ_BUILD)/seeds/$(t); \
	    mkdir -p $(FUZZ_BUILD)/seeds/$(t) $(FUZZ_BUILD)/corpus/$(t) $(FUZZ_BUILD)/artifacts/$(t); \
	    for f in $(FUZZ_SEEDS_$(t)); do \
	        cp "$$f" "$(FUZZ_BUILD)/seeds/$(t)/$$(echo "$$f" | sed "s|^\.\./||" | tr / _)"; done;)
	@fail=0; for t in $(FUZZ_TARGETS); do \
	    echo "== fuzz_$$t for $(FUZZ_SECONDS) s (log: $(FUZZ_BUILD)/fuzz_$$t.log)"; \
	    if LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	        $(FUZZ_BUILD)/fuzz_$$t $(FUZZ_OPTS) -max_total_time=$(FUZZ_SECONDS) \
	        -dict=tests/fuzz/$$t.dict -artifact_prefix=$(FUZZ_BUILD)/artifacts/$$t/ \
	        $(FUZZ_BUILD)/corpus/$$t $(FUZZ_BUILD)/seeds/$$t tests/fuzz/corpus/$$t \
	        tests/fuzz/regressions/$$t >$(FUZZ_BUILD)/fuzz_$$t.log 2>&1; then \
	        grep -h -e '^stat::number_of_executed_units' -e '^stat::new_units_added' \
	            -e '^stat::peak_rss_mb' $(FUZZ_BUILD)/fuzz_$$t.log | sed "s/^/  fuzz_$$t /"; \
	    else \
	        fail=1; tail -n 60 $(FUZZ_BUILD)/fuzz_$$t.log; \
	        echo "fuzz_$$t FAILED: the input is in $(FUZZ_BUILD)/artifacts/$$t/"; \
	    fi; \
	done; \
	if [ $$fail -ne 0 ]; then echo "make fuzz: FAILED"; exit 1; fi; echo "make fuzz: no failures"

# libstdc++ linked in (though nothing of ours needs it): AddressSanitizer intercepts C++'s
# __cxa_throw when the program starts, and assimp, loaded later by dlopen, throws (a .glb
# file's reader does even on good input); without the real function there, the first
# throw stops the program with "CHECK failed: ... real___cxa_throw".
ASAN_LIBS    := -Wl,--push-state,--no-as-needed -lstdc++ -Wl,--pop-state
asan:
	$(ASAN_ENV) $(MAKE) BUILD=$(ASAN_BUILD) CC=$(ASAN_CC) OPT='$(ASAN_FLAGS)' \
	    LDFLAGS='-fsanitize=address,undefined' EXTRA_LIBS='$(ASAN_LIBS)' test
