# sere — make | make run | make test | make bench | make deps | make install | make uninstall
#        make examples-check
#
# Every target that needs system libraries first runs scripts/deps.sh, which installs the
# missing Debian packages (only those) with apt-get.

PREFIX ?= /usr/local
BUILD  ?= build
ARCH   ?= -march=native
OPT    ?= -O3
SAN    ?=
# gcc and g++ unless given (make CC=clang CXX=clang++, or in the environment); make's own
# default (cc) does not count as given.
ifeq ($(origin CC),default)
CC     := gcc
endif
ifeq ($(origin CXX),default)
CXX    := g++
endif
CC_IS_CLANG  := $(shell $(CC) --version 2>/dev/null | grep -q clang && echo 1)
CXX_IS_CLANG := $(shell $(CXX) --version 2>/dev/null | grep -q clang && echo 1)

# The version lives in VERSION alone: it becomes sere_version() (-DSERE_VERSION on core/base.c),
# the shared library's file name and SONAME (libsere.so.MAJOR), sere.pc and the CMake package.
VERSION       := $(strip $(shell cat VERSION))
VERSION_MAJOR := $(word 1,$(subst ., ,$(VERSION)))
# The commit `sere --version` names: git's short hash, -dirty with uncommitted changes,
# "unknown" outside a git checkout; `make GIT_COMMIT=...` overrides it.
ifeq ($(origin GIT_COMMIT),undefined)
GIT_COMMIT := $(shell git --no-optional-locks rev-parse --short=12 HEAD 2>/dev/null)
ifneq ($(GIT_COMMIT),)
GIT_COMMIT := $(GIT_COMMIT)$(shell git --no-optional-locks diff --quiet HEAD -- 2>/dev/null || echo -dirty)
else
GIT_COMMIT := unknown
endif
endif

LEAF   ?= data/leaves/maple.leaf
PRESET ?= maple-red
FRAMES ?= 8000
POINTS ?= 1000
OUT    ?= out/run

WARN      := -Wall -Wextra -Wpedantic -Werror
# clang reports an `omp simd` loop it could not vectorize as -Wpass-failed (today the Eq. 12 loop
# of shrink.c and one in leaf.c, their gathers and bit selects). That is an optimization remark,
# not a defect in the code: gcc vectorizes those loops, clang runs them one element per step with
# the same results. So clang builds silence it; `make CC=clang CLANG_QUIET=` shows the loops.
CLANG_QUIET ?= -Wno-pass-failed
ifeq ($(CC_IS_CLANG),1)
WARN      += $(CLANG_QUIET)
endif
DEPFLAGS  := -MMD -MP
# -ffp-contract=off: no silent FMA contraction, so 1 and 2 threads (and the reference twins)
# round identically; determinism is a contract (docs/DESIGN.md). -fno-trapping-math: we never unmask
# floating-point exceptions, so the vectorizer may compute both sides of a select (a division
# included) instead of branching; -fno-math-errno: nothing reads errno after sqrt, so sqrt
# needs no branch to a library call for negative input. Neither changes a result (no
# reassociation, no contraction, the same correctly rounded sqrt).
COMMON    := $(OPT) $(ARCH) -g -ffp-contract=off -fno-trapping-math -fno-math-errno -fopenmp -fPIC $(DEPFLAGS)
ifeq ($(SAN),1)
COMMON    += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
LDSAN     := -fsanitize=address,undefined
endif
# No hardware gathers in loops gcc vectorizes on its own (-mtune-ctrl=^use_gather; gcc 12 tunes
# this Zen 4 as Zen 3, which allows them). A 512-bit gather issues one load a lane and is slower
# here than the scalar loads and inserts gcc emits instead: the osmosis step without its CG
# iterations 8–13% faster, the shrinkage 10%, the mass-spring step 4%, the crossing count 2–3%
# slower, the same bits (docs/PERFORMANCE.md, 2026-11-29). Intel parts with the Downfall
# microcode have slow gathers too. The lane layer's record loads never used them. An x86 switch
# of gcc's alone (clang 14 has none).
NO_GATHER := -mtune-ctrl=^use_gather
ifneq ($(filter x86_64-% i686-% i386-%,$(shell $(CC) -dumpmachine 2>/dev/null)),)
ifneq ($(CC_IS_CLANG),1)
COMMON_C   := $(NO_GATHER)
endif
ifneq ($(CXX_IS_CLANG),1)
COMMON_CXX := $(NO_GATHER)
endif
endif
INCLUDES  := -Ikernels -Iharness
CAIRO_CFLAGS := $(shell pkg-config --cflags cairo 2>/dev/null)
CAIRO_LIBS   := $(shell pkg-config --libs cairo 2>/dev/null || echo -lcairo)
CFLAGS_ALL   := -std=c17 $(COMMON) $(COMMON_C) $(WARN) $(INCLUDES)
HARNESS_CFLAGS := $(CFLAGS_ALL) $(CAIRO_CFLAGS) -DSERE_DATA_DIR='"$(PREFIX)/share/sere"'
CXXFLAGS_ALL := -std=c++17 $(COMMON) $(COMMON_CXX) $(WARN) $(INCLUDES) -isystem /usr/include/eigen3
# MPI when Open MPI's development files are there (scripts/deps.sh installs them): only
# the cmd_litter*.c files call it, so only they get the flags and -DSERE_MPI; without them the
# same sources build without MPI and sere litter runs every leaf in one process.
MPI_CFLAGS   := $(shell pkg-config --cflags ompi-c 2>/dev/null)
MPI_LIBS     := $(shell pkg-config --libs ompi-c 2>/dev/null)
LIBS_HARNESS := -lhwloc -lpng $(CAIRO_LIBS) $(MPI_LIBS) -lm

KERNEL_SRC  := $(sort $(wildcard kernels/*/*.c))
HARNESS_SRC := $(sort $(filter-out harness/cli/main.c,$(wildcard harness/*/*.c)))
TEST_SRC    := $(sort $(wildcard tests/*.c))
BENCH_SRC   := $(sort $(wildcard bench/*.cc))
TOOL_SRC    := $(sort $(wildcard data/tools/*.c))

KERNEL_OBJ  := $(KERNEL_SRC:%.c=$(BUILD)/obj/%.o)
HARNESS_OBJ := $(HARNESS_SRC:%.c=$(BUILD)/obj/%.o)
TEST_OBJ    := $(TEST_SRC:%.c=$(BUILD)/obj/%.o)
BENCH_OBJ   := $(BENCH_SRC:%.cc=$(BUILD)/obj/%.o)
MAIN_OBJ    := $(BUILD)/obj/harness/cli/main.o

LIB_A   := $(BUILD)/libsere.a
SONAME  := libsere.so.$(VERSION_MAJOR)
LIB_SO_REAL := $(BUILD)/libsere.so.$(VERSION)
LIB_SO_MAJOR := $(BUILD)/$(SONAME)
LIB_SO  := $(BUILD)/libsere.so
SERE    := $(BUILD)/sere
TESTS   := $(BUILD)/sere-tests
BENCHX  := $(BUILD)/sere-bench

.PHONY: all run test test-fast test-asan test-widths bench bench-table bench-table-check deps install uninstall examples-check header-check format \
	format-check clean
.DEFAULT_GOAL := all

all: $(LIB_A) $(LIB_SO) $(SERE)

# clang's -fopenmp needs LLVM's OpenMP runtime (libomp-dev), which Debian's clang does not pull in.
deps:
	@bash scripts/deps.sh $(if $(CC_IS_CLANG),clang libomp-dev)

run: deps
	@$(MAKE) --no-print-directory all
	$(SERE) run $(LEAF) --preset $(PRESET) --frames $(FRAMES) --points $(POINTS) --until-dry --out $(OUT)

# The suite, then the same suite under AddressSanitizer + UBSan; Criterion's summary closes.
test: deps
	@$(MAKE) --no-print-directory test-fast
	@$(MAKE) --no-print-directory test-asan

# TEST_FILTER=PATTERN runs only the tests it matches (Criterion's --filter, extended globs).
# SERE_ADAPTIVE_THREADS=0: the kernels use the threads they are given even when other processes
# hold cores, so that the tests comparing 1, 2 and 3 threads really run them.
test-fast: $(TESTS) $(SERE)
	SERE_ADAPTIVE_THREADS=0 SERE_BIN=$(SERE) $(TESTS) --jobs 1 $(if $(TEST_FILTER),--filter '$(TEST_FILTER)')

# OMPI_MCA_mca_base_env_list sets the environment of the ranks that mpirun starts (sere litter's
# MPI test). Open MPI's libraries have no frame pointers, so LeakSanitizer's fast unwinder stops
# in them; the ranks unwind fully (fast_unwind_on_malloc=0), down to the Open MPI library that
# tests/lsan.supp names. Only the ranks: everywhere it would slow every test down.
test-asan:
	@$(MAKE) --no-print-directory BUILD=build/asan SAN=1 OPT=-O1 build/asan/sere-tests build/asan/sere
	SERE_ADAPTIVE_THREADS=0 ASAN_OPTIONS=detect_leaks=1 \
	OMPI_MCA_mca_base_env_list='ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0' LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 SERE_BIN=build/asan/sere build/asan/sere-tests --jobs 1

# The SIMD lane layer (kernels/core/internal/simd.h) at its other widths: an AVX2 build (when this
# CPU has AVX2) and the portable 4-lane C build run the tests that pin a kernel's bits with a
# stored hash, so every width is checked to give the bits of the native one, and the skinning's
# bitwise test against its twin (its runs are found with the lane layer's integer compare).
WIDTH_TESTS ?= @(massspring/*|solvebits/*|skeleton/skinning*)
test-widths:
	@if grep -qw avx2 /proc/cpuinfo; then $(MAKE) --no-print-directory BUILD=build/avx2 ARCH=-march=x86-64-v3 build/avx2/sere-tests; fi
	@$(MAKE) --no-print-directory BUILD=build/portable ARCH=-march=x86-64 build/portable/sere-tests
	@for w in avx2 portable; do test -x build/$$w/sere-tests || continue; echo "width: $$w"; \
	  SERE_ADAPTIVE_THREADS=0 build/$$w/sere-tests --jobs 1 --filter '$(WIDTH_TESTS)' || exit 1; done

bench: deps
	@$(MAKE) --no-print-directory $(BENCHX)
	$(BENCHX) $(BENCH_ARGS)

# The README's kernel table from one run (scripts/bench-table.py names its benchmarks): each
# kernel, its floor and its peer at 1 and 2 threads, medians of BENCH_REPS repetitions, written to
# $(BUILD)/kernels.md beside the run's JSON. BEFORE=run.json (a run of another build) adds a column
# comparing the two.
BENCH_REPS ?= 5
bench-table: deps
	@$(MAKE) --no-print-directory $(BENCHX)
	$(BENCHX) --benchmark_repetitions=$(BENCH_REPS) --benchmark_report_aggregates_only=true \
		--benchmark_out=$(BUILD)/bench-table.json --benchmark_out_format=json \
		--benchmark_filter="$$(python3 scripts/bench-table.py --filter)"
	python3 scripts/bench-table.py $(BUILD)/bench-table.json $(if $(BEFORE),--before $(BEFORE)) > $(BUILD)/kernels.md
	@echo "bench-table: the table is $(BUILD)/kernels.md, the run $(BUILD)/bench-table.json"

# sere-bench builds, and has every benchmark the kernel table names (CI runs this).
bench-table-check: deps
	@$(MAKE) --no-print-directory $(BENCHX)
	$(BENCHX) --benchmark_list_tests | python3 scripts/bench-table.py --check-names -

$(BUILD)/obj/kernels/%.o: kernels/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/obj/harness/%.o: harness/%.c
	@mkdir -p $(dir $@)
	$(CC) $(HARNESS_CFLAGS) -c $< -o $@

# The version reaches the code as a define on core/base.c alone (sere_version()).
$(BUILD)/obj/kernels/core/base.o: CFLAGS_ALL += -DSERE_VERSION='"$(VERSION)"'
$(BUILD)/obj/kernels/core/base.o: VERSION

ifneq ($(MPI_LIBS),)
$(BUILD)/obj/harness/cli/cmd_litter.o $(BUILD)/obj/harness/cli/cmd_litter_world.o: HARNESS_CFLAGS += -DSERE_MPI $(MPI_CFLAGS)
endif

# The commit reaches main.c (sere --version) and machine.c (the machine facts of every result);
# the stamp changes only when the commit does, so both are rebuilt then and only then.
COMMIT_STAMP := $(BUILD)/gen/commit
$(shell mkdir -p $(BUILD)/gen && { [ "$$(cat $(COMMIT_STAMP) 2>/dev/null)" = "$(GIT_COMMIT)" ] || echo "$(GIT_COMMIT)" > $(COMMIT_STAMP); })
$(MAIN_OBJ) $(BUILD)/obj/harness/common/machine.o: HARNESS_CFLAGS += -DSERE_GIT_COMMIT='"$(GIT_COMMIT)"'
$(MAIN_OBJ) $(BUILD)/obj/harness/common/machine.o: $(COMMIT_STAMP)

$(BUILD)/obj/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(HARNESS_CFLAGS) -Itests -c $< -o $@

# hypre (BoomerAMG, the CG benchmark's peer): Debian builds it with MPI, whose headers and
# library pkg-config's mpi names (its C API only: no MPI C++ bindings to link).
HYPRE_CFLAGS := -isystem /usr/include/hypre $(patsubst -I%,-isystem %,$(shell pkg-config --cflags mpi 2>/dev/null)) \
                -DOMPI_SKIP_MPICXX -DMPICH_SKIP_MPICXX
HYPRE_LIBS   := -lHYPRE $(shell pkg-config --libs mpi 2>/dev/null)

# gcc 12 reports a false maybe-uninitialized inside Eigen's AVX-512 reductions (system header
# code inlined into the Eigen peer); everything else stays -Werror. (clang has no such warning.)
$(BUILD)/obj/bench/%.o: bench/%.cc
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(if $(CXX_IS_CLANG),,-Wno-maybe-uninitialized) -isystem /usr/include/embree3 $(HYPRE_CFLAGS) -Ibench -c $< -o $@

$(LIB_A): $(KERNEL_OBJ)
	@rm -f $@
	ar rcs $@ $^

# libsere.so.MAJOR.MINOR.PATCH with SONAME libsere.so.MAJOR, and the two usual symlinks.
$(LIB_SO_REAL): $(KERNEL_OBJ)
	$(CC) -shared -fopenmp $(LDSAN) -Wl,-soname,$(SONAME) -o $@ $^ -lm

$(LIB_SO_MAJOR): $(LIB_SO_REAL)
	ln -sf $(notdir $<) $@

$(LIB_SO): $(LIB_SO_MAJOR)
	ln -sf $(notdir $<) $@

$(SERE): $(MAIN_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CC) -fopenmp $(LDSAN) -o $@ $(MAIN_OBJ) $(HARNESS_OBJ) $(LIB_A) $(LIBS_HARNESS)

# assimp: the tests open sere litter's .glb with a real glTF reader.
$(TESTS): $(TEST_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CC) -fopenmp $(LDSAN) -o $@ $(TEST_OBJ) $(HARNESS_OBJ) $(LIB_A) -lcriterion -lassimp $(LIBS_HARNESS)

# leafgen writes the shipped leaves (data/tools/leafgen.c): `build/leafgen data/leaves`.
LEAFGEN_SRC := $(filter data/tools/leafgen%.c,$(TOOL_SRC))
LEAFGEN_OBJ := $(LEAFGEN_SRC:%.c=$(BUILD)/obj/%.o)
$(BUILD)/obj/data/tools/%.o: data/tools/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/leafgen: $(LEAFGEN_OBJ) $(BUILD)/obj/harness/read/leaffile.o $(BUILD)/obj/harness/common/io.o $(LIB_A)
	$(CC) -fopenmp $(LDSAN) -o $@ $^ -lm

$(BENCHX): $(BENCH_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CXX) -fopenmp $(LDSAN) -o $@ $(BENCH_OBJ) $(HARNESS_OBJ) $(LIB_A) -lbenchmark -lpthread -lembree3 $(HYPRE_LIBS) $(LIBS_HARNESS)

# Installed layout (all relative to PREFIX, so the tree can be moved as a whole: sere finds
# ../share/sere beside its own binary, sere.pc and the CMake package locate themselves):
#   bin/sere, lib/libsere.{a,so.VERSION} with the symlinks libsere.so.MAJOR and libsere.so,
#   lib/pkgconfig/sere.pc, lib/cmake/sere/sereConfig{,Version}.cmake,
#   include/sere/sere.h and include/sere/ROOM/*.h (the public headers, in their rooms: core, mesh,
#   solve, drying, season, wilt), include/sere/ref/*.h (the reference twins),
#   share/sere/{presets,leaves,seasons,masks,skeletons}.
# Every directory install creates is listed in share/sere/installed-dirs, so that uninstall
# removes exactly what install put there: the files below, then those directories if empty.
DEST          := $(DESTDIR)$(PREFIX)
# A room's internal/ headers are private to the room: not installed.
PUBLIC_H      := kernels/sere.h $(sort $(filter-out kernels/ref/%,$(wildcard kernels/*/*.h)))
PUBLIC_ROOMS  := $(sort $(patsubst kernels/%/,%,$(dir $(filter-out kernels/sere.h,$(PUBLIC_H)))))
REF_H         := $(sort $(wildcard kernels/ref/*.h))
DATA_SUBDIRS  := presets leaves seasons masks skeletons
DATA_FILES    := $(sort $(shell cd data && find $(DATA_SUBDIRS) -type f 2>/dev/null))
DATA_DIRS     := $(sort $(shell cd data && find $(DATA_SUBDIRS) -type d 2>/dev/null))
INSTALL_DIRS  := bin lib lib/pkgconfig lib/cmake lib/cmake/sere include include/sere include/sere/ref \
	$(addprefix include/sere/,$(PUBLIC_ROOMS)) share \
	share/sere $(addprefix share/sere/,$(DATA_DIRS))
INSTALL_FILES := bin/sere lib/libsere.a lib/libsere.so.$(VERSION) lib/$(SONAME) lib/libsere.so \
	lib/pkgconfig/sere.pc lib/cmake/sere/sereConfig.cmake lib/cmake/sere/sereConfigVersion.cmake \
	$(patsubst kernels/%,include/sere/%,$(PUBLIC_H)) $(addprefix include/sere/ref/,$(notdir $(REF_H))) \
	$(addprefix share/sere/,$(DATA_FILES)) share/sere/installed-dirs
SUBST         := sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@VERSION_MAJOR@|$(VERSION_MAJOR)|g'

install: all
	@[ -n "$(PREFIX)" ] || { echo "install: PREFIX is empty" >&2; exit 1; }
	@created=""; for d in "" $(INSTALL_DIRS); do \
		if [ ! -d "$(DEST)/$$d" ]; then install -d "$(DEST)/$$d" && created="$$created$${d:-.}\n"; fi; \
	done; printf "$$created" >> "$(DEST)/share/sere/installed-dirs"
	install -m 755 $(SERE) $(DEST)/bin/
	install -m 644 $(LIB_A) $(DEST)/lib/
	install -m 755 $(LIB_SO_REAL) $(DEST)/lib/
	ln -sf libsere.so.$(VERSION) $(DEST)/lib/$(SONAME)
	ln -sf $(SONAME) $(DEST)/lib/libsere.so
	$(SUBST) scripts/sere.pc.in > $(DEST)/lib/pkgconfig/sere.pc
	$(SUBST) cmake/sereConfig.cmake.in > $(DEST)/lib/cmake/sere/sereConfig.cmake
	$(SUBST) cmake/sereConfigVersion.cmake.in > $(DEST)/lib/cmake/sere/sereConfigVersion.cmake
	@for h in $(PUBLIC_H); do echo "install -m 644 $$h $(DEST)/include/sere/$${h#kernels/}"; \
		install -m 644 "$$h" "$(DEST)/include/sere/$${h#kernels/}" || exit 1; done
	install -m 644 $(REF_H) $(DEST)/include/sere/ref/
	@for f in $(DATA_FILES); do echo "install -m 644 data/$$f $(DEST)/share/sere/$$f"; \
		install -m 644 "data/$$f" "$(DEST)/share/sere/$$f" || exit 1; done

uninstall:
	@[ -n "$(PREFIX)" ] || { echo "uninstall: PREFIX is empty" >&2; exit 1; }
	@dirs=""; [ -f "$(DEST)/share/sere/installed-dirs" ] && dirs=$$(cat "$(DEST)/share/sere/installed-dirs"); \
	for f in $(INSTALL_FILES); do \
		if [ -e "$(DEST)/$$f" ] || [ -L "$(DEST)/$$f" ]; then echo "rm $(DEST)/$$f"; rm -f "$(DEST)/$$f"; fi; \
	done; \
	for d in $$(printf '%s\n' $$dirs | sort -r); do \
		[ "$$d" = . ] && d=""; rmdir "$(DEST)/$$d" 2>/dev/null && echo "rmdir $(DEST)/$$d"; \
	done; true

# The layering of the rooms (scripts/layer-check.sh), the equation table (docs/EQUATIONS.md), the
# sizes (scripts/size-check.py: no file over 1000 lines, no function over 120), then the headers as a
# user gets them: each compiles alone as C17 and as C++17 with every warning an error, and sere.h
# includes every public header.
header-check:
	@bash scripts/layer-check.sh
	@python3 scripts/equations-check.py
	@python3 scripts/size-check.py
	@for h in $(filter-out kernels/sere.h,$(PUBLIC_H)); do \
		grep -q "^#include \"$${h#kernels/}\"" kernels/sere.h || { echo "kernels/sere.h does not include $${h#kernels/}" >&2; exit 1; }; \
	done
	@mkdir -p $(BUILD)/header-check
	@for h in $(PUBLIC_H) $(REF_H); do \
		echo "#include \"$(CURDIR)/$$h\"" > $(BUILD)/header-check/h.c; \
		$(CC) -std=c17 $(WARN) -fsyntax-only -Ikernels $(BUILD)/header-check/h.c || { echo "$$h does not compile alone (C)" >&2; exit 1; }; \
		cp $(BUILD)/header-check/h.c $(BUILD)/header-check/h.cc; \
		$(CXX) -std=c++17 $(WARN) -fsyntax-only -Ikernels $(BUILD)/header-check/h.cc || { echo "$$h does not compile alone (C++)" >&2; exit 1; }; \
	done
	@echo "header-check: $(words $(PUBLIC_H) $(REF_H)) headers compile alone (C17, C++17); sere.h includes every public one"

# Installs into a scratch prefix, then builds and runs examples/ against it twice: through
# pkg-config (examples/Makefile) and through CMake's find_package(sere) (examples/CMakeLists.txt).
# Each example checks its own result and exits non-zero on failure.
EXCHECK := $(abspath $(BUILD))/examples-check
examples-check: header-check
	@bash scripts/deps.sh cmake
	rm -rf $(EXCHECK)
	@$(MAKE) --no-print-directory install PREFIX=$(EXCHECK)/prefix
	PKG_CONFIG_PATH=$(EXCHECK)/prefix/lib/pkgconfig $(MAKE) --no-print-directory -C examples CC=$(CC) \
		OUT=$(EXCHECK)/pkgconfig check
	cmake -S examples -B $(EXCHECK)/cmake -DCMAKE_PREFIX_PATH=$(EXCHECK)/prefix -DCMAKE_C_COMPILER=$(CC) \
		-DCMAKE_BUILD_TYPE=Release
	cmake --build $(EXCHECK)/cmake
	cd $(EXCHECK)/cmake && ctest --output-on-failure
	@$(MAKE) --no-print-directory uninstall PREFIX=$(EXCHECK)/prefix >/dev/null
	@[ ! -e $(EXCHECK)/prefix ] || { echo "uninstall left:" >&2; find $(EXCHECK)/prefix >&2; exit 1; }
	@echo "examples-check: the three examples pass through pkg-config and CMake; uninstall removed every file"

format:
	clang-format -i $(KERNEL_SRC) $(wildcard kernels/*.h kernels/*/*.h kernels/*/internal/*.h) $(HARNESS_SRC) harness/cli/main.c $(wildcard harness/*/*.h) $(TEST_SRC) $(wildcard tests/*.h) $(BENCH_SRC) $(wildcard bench/*.h) $(TOOL_SRC) \
		$(wildcard examples/*.c)

format-check:
	clang-format --dry-run -Werror $(KERNEL_SRC) $(wildcard kernels/*.h kernels/*/*.h kernels/*/internal/*.h) $(HARNESS_SRC) harness/cli/main.c $(wildcard harness/*/*.h) $(TEST_SRC) $(wildcard tests/*.h) $(BENCH_SRC) $(wildcard bench/*.h) $(TOOL_SRC) \
		$(wildcard examples/*.c)

clean:
	rm -rf build

-include $(KERNEL_OBJ:.o=.d) $(HARNESS_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(BENCH_OBJ:.o=.d) $(MAIN_OBJ:.o=.d) $(LEAFGEN_OBJ:.o=.d)

# ---- fuzz: libFuzzer targets for the readers (fuzz/README.md) ------------------------------------
# `make fuzz FUZZ_SECONDS=N` builds, with clang, one libFuzzer target per reader in build/fuzz
# (the library and harness instrumented too, -fsanitize=fuzzer,address,undefined) and runs each
# for N seconds on seeds copied from data/ and tests/data/bad/; it prints every target's
# executions and coverage and exits non-zero on any finding. `make fuzz-build` only builds.
FUZZ_SECONDS ?= 30
FUZZ_CC      ?= clang
FUZZ_BUILD   ?= build/fuzz
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
FUZZ_CFLAGS  := -std=c17 -O1 -g $(ARCH) -ffp-contract=off -fno-trapping-math -fno-math-errno -fopenmp $(DEPFLAGS) \
	-Wall -Wextra -Wpedantic -Werror -Wno-pass-failed $(FUZZ_SAN) $(INCLUDES) $(CAIRO_CFLAGS) \
	-DSERE_DATA_DIR='"$(PREFIX)/share/sere"'
FUZZ_NAMES   := $(sort $(basename $(notdir $(wildcard fuzz/fuzz_*.c))))
FUZZ_BINS    := $(addprefix $(FUZZ_BUILD)/,$(FUZZ_NAMES))
FUZZ_LIB_OBJ := $(KERNEL_SRC:%.c=$(FUZZ_BUILD)/obj/%.o) $(HARNESS_SRC:%.c=$(FUZZ_BUILD)/obj/%.o)
FUZZ_LIB     := $(FUZZ_BUILD)/libsere-fuzz.a
FUZZ_SHIM    := $(FUZZ_BUILD)/obj/fuzz/seasonleaf_shim.o

.PHONY: fuzz fuzz-build
fuzz-build:
	@bash scripts/deps.sh clang libomp-dev
	@$(MAKE) --no-print-directory $(FUZZ_BINS)

fuzz: fuzz-build
	bash fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_BINS)

# The library and harness with coverage instrumentation for the fuzzer (fuzzer-no-link); the
# targets pull from the archive only what they use.
$(FUZZ_BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@

$(FUZZ_BUILD)/obj/kernels/core/base.o: FUZZ_CFLAGS += -DSERE_VERSION='"$(VERSION)"'

$(FUZZ_LIB): $(FUZZ_LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

# fuzz_chain and fuzz_png also reach two static readers of harness/read/seasonleaf.c through the shim.
$(FUZZ_BUILD)/fuzz_chain $(FUZZ_BUILD)/fuzz_png: $(FUZZ_SHIM)
# fuzz_png recomputes chunk CRCs with zlib's crc32.
$(FUZZ_BUILD)/fuzz_png: FUZZ_LIBS := -lz

$(FUZZ_BUILD)/fuzz_%: $(FUZZ_BUILD)/obj/fuzz/fuzz_%.o $(FUZZ_LIB)
	$(FUZZ_CC) -fsanitize=fuzzer $(FUZZ_SAN) -fopenmp -o $@ $< $(filter $(FUZZ_SHIM),$^) $(FUZZ_LIB) $(LIBS_HARNESS) $(FUZZ_LIBS)

-include $(FUZZ_LIB_OBJ:.o=.d) $(FUZZ_BUILD)/obj/fuzz/*.d
.SECONDARY: $(FUZZ_NAMES:%=$(FUZZ_BUILD)/obj/fuzz/%.o)
