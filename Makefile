# sere — make | make run | make test | make bench | make deps | make install
#
# Every target that needs system libraries first runs scripts/deps.sh, which installs the
# missing Debian packages (only those) with apt-get.

PREFIX ?= /usr/local
BUILD  ?= build
ARCH   ?= -march=native
OPT    ?= -O3
SAN    ?=
CC     := gcc
CXX    := g++

LEAF   ?= data/leaves/maple.leaf
PRESET ?= maple-red
FRAMES ?= 8000
POINTS ?= 1000
OUT    ?= out/run

WARN      := -Wall -Wextra -Wpedantic -Werror
DEPFLAGS  := -MMD -MP
# -ffp-contract=off: no silent FMA contraction, so 1 and 2 threads (and the reference twins)
# round identically; determinism is a contract (DESIGN.md). -fno-trapping-math: we never unmask
# floating-point exceptions, so the vectorizer may compute both sides of a select (a division
# included) instead of branching; -fno-math-errno: nothing reads errno after sqrt, so sqrt
# needs no branch to a library call for negative input. Neither changes a result (no
# reassociation, no contraction, the same correctly rounded sqrt).
COMMON    := $(OPT) $(ARCH) -g -ffp-contract=off -fno-trapping-math -fno-math-errno -fopenmp -fPIC $(DEPFLAGS)
ifeq ($(SAN),1)
COMMON    += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
LDSAN     := -fsanitize=address,undefined
endif
INCLUDES  := -Ikernels -Iharness
CAIRO_CFLAGS := $(shell pkg-config --cflags cairo 2>/dev/null)
CAIRO_LIBS   := $(shell pkg-config --libs cairo 2>/dev/null || echo -lcairo)
CFLAGS_ALL   := -std=c17 $(COMMON) $(WARN) $(INCLUDES)
HARNESS_CFLAGS := $(CFLAGS_ALL) $(CAIRO_CFLAGS) -DSERE_DATA_DIR='"$(PREFIX)/share/sere"'
CXXFLAGS_ALL := -std=c++17 $(COMMON) $(WARN) $(INCLUDES) -isystem /usr/include/eigen3
LIBS_HARNESS := -lhwloc -lpng $(CAIRO_LIBS) -lm

KERNEL_SRC  := $(sort $(wildcard kernels/*.c kernels/ref/*.c))
HARNESS_SRC := $(sort $(filter-out harness/main.c,$(wildcard harness/*.c)))
TEST_SRC    := $(sort $(wildcard tests/*.c))
BENCH_SRC   := $(sort $(wildcard bench/*.cc))
TOOL_SRC    := $(sort $(wildcard data/tools/*.c))

KERNEL_OBJ  := $(KERNEL_SRC:%.c=$(BUILD)/obj/%.o)
HARNESS_OBJ := $(HARNESS_SRC:%.c=$(BUILD)/obj/%.o)
TEST_OBJ    := $(TEST_SRC:%.c=$(BUILD)/obj/%.o)
BENCH_OBJ   := $(BENCH_SRC:%.cc=$(BUILD)/obj/%.o)
MAIN_OBJ    := $(BUILD)/obj/harness/main.o

LIB_A   := $(BUILD)/libsere.a
LIB_SO  := $(BUILD)/libsere.so
SERE    := $(BUILD)/sere
TESTS   := $(BUILD)/sere-tests
BENCHX  := $(BUILD)/sere-bench

.PHONY: all run test test-fast test-asan bench deps install format format-check clean
.DEFAULT_GOAL := all

all: $(LIB_A) $(LIB_SO) $(SERE)

deps:
	@bash scripts/deps.sh

run: deps
	@$(MAKE) --no-print-directory all
	$(SERE) run $(LEAF) --preset $(PRESET) --frames $(FRAMES) --points $(POINTS) --until-dry --out $(OUT)

# The suite, then the same suite under AddressSanitizer + UBSan; Criterion's summary closes.
test: deps
	@$(MAKE) --no-print-directory test-fast
	@$(MAKE) --no-print-directory test-asan

test-fast: $(TESTS) $(SERE)
	SERE_BIN=$(SERE) $(TESTS) --jobs 1

test-asan:
	@$(MAKE) --no-print-directory BUILD=build/asan SAN=1 OPT=-O1 build/asan/sere-tests build/asan/sere
	ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp SERE_BIN=build/asan/sere build/asan/sere-tests --jobs 1

bench: deps
	@$(MAKE) --no-print-directory $(BENCHX)
	$(BENCHX) $(BENCH_ARGS)

$(BUILD)/obj/kernels/%.o: kernels/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/obj/harness/%.o: harness/%.c
	@mkdir -p $(dir $@)
	$(CC) $(HARNESS_CFLAGS) -c $< -o $@

$(BUILD)/obj/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(HARNESS_CFLAGS) -Itests -c $< -o $@

# gcc 12 reports a false maybe-uninitialized inside Eigen's AVX-512 reductions (system header
# code inlined into the Eigen peer); everything else stays -Werror.
$(BUILD)/obj/bench/%.o: bench/%.cc
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) -Wno-maybe-uninitialized -isystem /usr/include/embree3 -Ibench -c $< -o $@

$(LIB_A): $(KERNEL_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(LIB_SO): $(KERNEL_OBJ)
	$(CC) -shared -fopenmp $(LDSAN) -o $@ $^ -lm

$(SERE): $(MAIN_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CC) -fopenmp $(LDSAN) -o $@ $(MAIN_OBJ) $(HARNESS_OBJ) $(LIB_A) $(LIBS_HARNESS)

$(TESTS): $(TEST_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CC) -fopenmp $(LDSAN) -o $@ $(TEST_OBJ) $(HARNESS_OBJ) $(LIB_A) -lcriterion $(LIBS_HARNESS)

$(BENCHX): $(BENCH_OBJ) $(HARNESS_OBJ) $(LIB_A)
	$(CXX) -fopenmp $(LDSAN) -o $@ $(BENCH_OBJ) $(HARNESS_OBJ) $(LIB_A) -lbenchmark -lpthread -lembree3 $(LIBS_HARNESS)

install: all
	install -d $(DESTDIR)$(PREFIX)/include/sere $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/bin
	install -m 644 kernels/*.h $(DESTDIR)$(PREFIX)/include/sere/
	install -m 644 $(LIB_A) $(LIB_SO) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SERE) $(DESTDIR)$(PREFIX)/bin/
	sed -e 's|@PREFIX@|$(PREFIX)|g' scripts/sere.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/sere.pc
	install -d $(DESTDIR)$(PREFIX)/share/sere
	cp -r data/presets data/leaves data/seasons data/masks $(wildcard data/skeletons) $(DESTDIR)$(PREFIX)/share/sere/

format:
	clang-format -i $(KERNEL_SRC) $(wildcard kernels/*.h kernels/ref/*.h) harness/*.c $(wildcard harness/*.h) $(TEST_SRC) $(wildcard tests/*.h) $(BENCH_SRC) $(wildcard bench/*.h) $(TOOL_SRC)

format-check:
	clang-format --dry-run -Werror $(KERNEL_SRC) $(wildcard kernels/*.h kernels/ref/*.h) harness/*.c $(wildcard harness/*.h) $(TEST_SRC) $(wildcard tests/*.h) $(BENCH_SRC) $(wildcard bench/*.h) $(TOOL_SRC)

clean:
	rm -rf build

-include $(KERNEL_OBJ:.o=.d) $(HARNESS_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(BENCH_OBJ:.o=.d) $(MAIN_OBJ:.o=.d)
