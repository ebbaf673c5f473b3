# gridbvh - see README.md.
#   make            optimized library, tools and experiments (bin/)
#   make test       the test suite (T=grid: the grid family, test_grid*.c, whose
#                   tests are named grid_*; T=conformance_grid: one test by its
#                   exact name; T='*word*': every test whose name contains word;
#                   T=a,b: several; T=--list names them; KINDS=grid,bvh: only
#                   these accelerator kinds; a T or KINDS matching nothing fails;
#                   tests/README.md). The last line: N passed, N failed, N skipped
#   make report     runs every experiment and rewrites REPORT.md and report/ once
#                   every experiment has finished (QUICK=1: smoke run into
#                   build/quick-report/, QUICK=0 or unset: the full run;
#                   KINDS=grid,bvh: only these kinds; ACCEL="bvh:width=4 ...": add
#                   specs; SCENES="my.scene mesh.off": exactly these scenes)
#   make sanitize   the test suite under AddressSanitizer + UBSan
#   make fuzz       libFuzzer targets for the loaders (clang)
#   make lab        the lab (LAB.md; STEP=n checks step n), make lab-report
#   make embree     the optional Embree reference (EMBREE_CFLAGS, EMBREE_LIBS)
# The variables a command line may set (any other, e.g. a typo such as QUIK=1
# or SCENE=x, is an error before any work):
#   build:  CC CXX ARCH ARCH512 OPT CFLAGS LDLIBS BUILD BIN EMBREE_CFLAGS EMBREE_LIBS
#   runs:   T J KINDS QUICK ACCEL SCENES STEP LAB
# Booleans (QUICK, LAB) take 1 (on) or 0 (off; the same as unset).
KNOWN_VARS := CC CXX ARCH ARCH512 OPT CFLAGS LDLIBS BUILD BIN EMBREE_CFLAGS EMBREE_LIBS \
              T J KINDS QUICK ACCEL SCENES STEP LAB
BOOL_VARS  := QUICK LAB
# make's own variables, which a command line or a recursive make may set.
MAKE_VARS  := MAKEFLAGS MFLAGS MAKEOVERRIDES MAKELEVEL MAKE SHELL .SHELLFLAGS
CMDLINE_VARS := $(foreach v,$(.VARIABLES),$(if $(filter command line,$(origin $(v))),$(v)))
UNKNOWN_VARS := $(filter-out $(KNOWN_VARS) $(MAKE_VARS),$(CMDLINE_VARS))
ifneq ($(UNKNOWN_VARS),)
$(error unknown variable $(UNKNOWN_VARS) on the command line; known: $(KNOWN_VARS) (the header of Makefile says what each does))
endif
$(foreach v,$(BOOL_VARS),$(if $(filter-out 0 1,$($(v))),$(error $(v)=$($(v)): $(v) takes 1 (on) or 0 (off))))
CC      ?= cc
# The baseline instruction set of every unit is AVX2 (x86-64-v3), whatever
# the build machine; the kernel units (SLOW_SRC: the wide BVH's, instanced/'s
# and the grid family's block kernels) are compiled a second time with ARCH512 and picked at run time where the CPU has it
# (accel/core/isa.c; GRIDBVH_ISA=avx2 forces the baseline). By default that
# second copy is built only where it can run: when the build machine's CPU
# has x86-64-v4's AVX-512 (avx512f, cd, bw, dq and vl in /proc/cpuinfo).
# Elsewhere no run could select it, and it was half the kernels' compile
# work (9 of the 18 slowest units). ARCH512=-march=x86-64-v4 builds it
# anyway (a binary for another machine); ARCH512= (empty) or a compiler that
# refuses it builds the AVX2 kernels only.
ARCH    ?= -march=x86-64-v3
CPU_512 := $(shell awk '/^flags/ { n = 0; for (i = 1; i <= NF; i++) if ($$i ~ /^avx512(f|cd|bw|dq|vl)$$/) n++; \
                  print n == 5 ? "-march=x86-64-v4" : ""; exit }' /proc/cpuinfo 2>/dev/null)
ARCH512 ?= $(CPU_512)
OPT     ?= -O3
CFLAGS  ?= $(OPT) $(ARCH) -g
# Flags every build needs, kept apart so that `make CFLAGS=...` cannot drop them.
BASE_CFLAGS := -std=c11 -D_GNU_SOURCE -Wall -Wextra -pthread -Iaccel -I.
ALL_CFLAGS = $(BASE_CFLAGS) $(CFLAGS)
LDLIBS  += -lm -pthread
BUILD   ?= build
BIN     ?= bin
# Builds use every core unless the caller chose (make -jN): `make test` on a
# clean clone compiles about 120 files before the tests start.
ifeq ($(filter -j%,$(MAKEFLAGS)),)
MAKEFLAGS += -j$(shell getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)
endif

# The library's sources and the backend discovery rule (shared with tests/fuzz).
ROOT :=
include sources.mk
ifeq ($(LAB),1)
LIB_SRC     += lab/student.c lab/student_grid.c
BASE_CFLAGS += -DGRIDBVH_LAB
endif
LIB_OBJ  := $(LIB_SRC:%.c=$(BUILD)/%.o)
# The AVX-512 twins of the kernel units: the same sources with ARCH512 in
# place of ARCH and WIDE_AVX512_UNIT defined (their symbols end in _avx512,
# bvh/wide/node.h, core/isa.h), linked beside the AVX2 ones. ISA_DISPATCH:
# the units that pick a twin by a structure's isa, compiled with
# GRIDBVH_AVX512 where the twins are linked.
ISA_DISPATCH := accel/core/isa.c bvh/wide/trace.c instanced/inst_packet.c grid/grid_trace.c \
                grid/grid_packet_trace.c nested_grid/ngrid_trace.c nested_grid/ngrid_packet.c \
                irregular_grid/igrid_trace.c
HAVE_512 := $(if $(strip $(ARCH512)),$(shell $(CC) $(ARCH512) -x c -c /dev/null -o /dev/null 2>/dev/null && echo 1))
ifeq ($(HAVE_512),1)
SLOW_512 := $(SLOW_SRC:%.c=$(BUILD)/%.avx512.o)
LIB_OBJ  := $(SLOW_512) $(LIB_OBJ)
$(ISA_DISPATCH:%.c=$(BUILD)/%.o): ALL_CFLAGS += -DGRIDBVH_AVX512
endif
LIB      := $(BUILD)/libgridbvh.a
# The kernel units first compiled (SLOW_SRC, sources.mk) keep line tables
# only (-g1) where the build asks for -g: full debug information of their
# forced-inline copies was 40% of their compile time (bvh/wide/
# k4_packet_hit.c: 12.0 s with -g, 7.5 s with -g1), and line tables are what
# perf and a backtrace need. GCC's code does not depend on the debug level.
$(SLOW_SRC:%.c=$(BUILD)/%.o) $(SLOW_512): ALL_CFLAGS += $(if $(filter -g,$(CFLAGS)),-g1)
# The same for the other units that instantiate kernel tables (core/
# variant.h: 5 to 9 forced-inline copies of a kernel per table): every
# kind's trace units, brute, the lab's kinds and the tests' lab solution.
KERNEL_SRC := $(shell grep -l -E 'ACCEL_KERNEL_(PAIR|TABLE)|GRID_KERNELS' \
                $(filter-out $(SLOW_SRC),$(LIB_SRC)) lab/*.c tests/*.c 2>/dev/null)
$(KERNEL_SRC:%.c=$(BUILD)/%.o): ALL_CFLAGS += $(if $(filter -g,$(CFLAGS)),-g1)
# Header dependencies come from the compiler (-MMD -MP, the .d files); a
# change of compiler or flags rebuilds everything through the flags stamp.
DEPFLAGS  = -MMD -MP
FLAGS_STAMP := $(BUILD)/.flags

# tools/embree_ref.c is optional (libembree-dev): only `make embree` builds it.
TOOLS    := $(patsubst tools/%.c,$(BIN)/%,$(filter-out tools/embree_ref.c,$(wildcard tools/*.c)))
# experiments/engine/: the measurement, statistics, tally and report
# assembly shared by every experiment (its README); experiments/*.c beside
# it: each experiment's own question and the helpers only it uses.
EXP_LIB  := $(filter-out experiments/exp_%.c experiments/engine/mkreport.c,$(wildcard experiments/*.c experiments/engine/*.c))
EXP_BINS := $(patsubst experiments/%.c,$(BIN)/%,$(wildcard experiments/exp_*.c))
# The lab's checks and its untouched starter kind are part of the tests
# (tests/test_lab.c: every check passes on the project and fails on the starter).
TEST_SRC := $(wildcard tests/*.c) lab/check.c lab/check_common.c lab/check_step3.c lab/starter.c \
            lab/check_step5.c \
            lab/check_top.c \
            lab/grid_starter.c \
            experiments/engine/claims.c experiments/engine/stats.c experiments/engine/svg.c \
            experiments/engine/mdcut.c

.PHONY: all test report sanitize fuzz clean bench lab lab-report embree embree-header FORCE
all: $(TOOLS) $(EXP_BINS) $(BIN)/mkreport $(BIN)/run_tests

$(FLAGS_STAMP): FORCE
	@mkdir -p $(dir $@)
	@echo '$(CC) $(ALL_CFLAGS) $(LDLIBS) 512:$(HAVE_512) $(ARCH512)' | cmp -s - $@ || \
	  echo '$(CC) $(ALL_CFLAGS) $(LDLIBS) 512:$(HAVE_512) $(ARCH512)' > $@

$(BUILD)/%.o: %.c $(FLAGS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(DEPFLAGS) -c $< -o $@

ifeq ($(HAVE_512),1)
$(SLOW_512): $(BUILD)/%.avx512.o: %.c $(FLAGS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(filter-out $(ARCH),$(ALL_CFLAGS)) $(ARCH512) -DWIDE_AVX512_UNIT $(DEPFLAGS) -c $< -o $@
endif

$(LIB): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

EXP_OBJ  := $(EXP_LIB:%.c=$(BUILD)/%.o)
TEST_OBJ := $(TEST_SRC:%.c=$(BUILD)/%.o)
# The tests' own units compile at -O1 where the build asks for -O2 or -O3:
# they time nothing (speed targets live in the report) and call the
# library's kernels, which keep the build's level; their 70 units were a
# sixth of a fresh build's compile work (23 s of CPU at -O3, 14 s at -O1,
# issue 53). The shared experiment units they link keep the build's level.
# (A rule of their own, not a target-specific ALL_CFLAGS: that would reach
# the flags stamp, their prerequisite, and rebuild everything.)
TEST_CFLAGS = $(BASE_CFLAGS) $(patsubst -O2,-O1,$(patsubst -O3,-O1,$(CFLAGS)))
$(BUILD)/tests/%.o: tests/%.c $(FLAGS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) $(DEPFLAGS) -c $< -o $@

# A tool's own pieces, if any: tools/<tool>/*.c.
# (tools/embree_ref/: only `make embree` builds it)
TOOL_PARTS := $(patsubst %.c,$(BUILD)/%.o,$(filter-out tools/embree_ref/%,$(wildcard tools/*/*.c)))
$(TOOLS): $(TOOL_PARTS)
$(BIN)/%: $(BUILD)/tools/%.o $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $< $(patsubst %.c,$(BUILD)/%.o,$(wildcard tools/$*/*.c)) $(LIB) -o $@ $(LDLIBS)

# The optional industrial reference (README.md): bin/embree_ref, Embree 3
# on the project's triangles and rays, built only here and only when the
# Debian package libembree-dev is installed (EMBREE_CFLAGS / EMBREE_LIBS for
# another install). make, make test and make report never need it.
EMBREE_CFLAGS ?=
EMBREE_LIBS   ?= -lembree3
embree: $(BIN)/embree_ref
embree-header:
	@printf '#include <embree3/rtcore.h>\n' | $(CC) $(EMBREE_CFLAGS) -E -x c - -o /dev/null 2>/dev/null || \
	  { echo "make embree: libembree-dev not installed (no embree3/rtcore.h; EMBREE_CFLAGS=-I... if elsewhere)"; exit 1; }

# Its own compile line, after the header check: a target-specific
# ALL_CFLAGS would reach the flags stamp (a prerequisite) and rebuild all.
$(BUILD)/tools/embree_ref.o: tools/embree_ref.c $(FLAGS_STAMP) | embree-header
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(EMBREE_CFLAGS) $(DEPFLAGS) -c $< -o $@
$(BIN)/embree_ref: $(BUILD)/tools/embree_ref.o $(patsubst %.c,$(BUILD)/%.o,$(wildcard tools/embree_ref/*.c)) $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $^ -o $@ $(LDLIBS) $(EMBREE_LIBS)

$(BIN)/exp_%: $(BUILD)/experiments/exp_%.o $(EXP_OBJ) $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $< $(EXP_OBJ) $(LIB) -o $@ $(LDLIBS)

$(BIN)/mkreport: $(BUILD)/experiments/engine/mkreport.o $(BUILD)/experiments/engine/mdcut.o \
                 $(BUILD)/experiments/engine/claims.o
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $^ -o $@ $(LDLIBS)

$(BIN)/lab: $(BUILD)/lab/lab.o $(BUILD)/lab/check.o $(BUILD)/lab/check_common.o $(BUILD)/lab/check_step3.o \
            $(BUILD)/lab/check_step5.o $(BUILD)/lab/check_top.o $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $^ -o $@ $(LDLIBS)

# The lab's checks run the student's code under AddressSanitizer and UBSan
# where the compiler has them (LAB.md): bin-lab/lab-safe is bin-lab/lab with
# lab/student*.c compiled instrumented and linked before the library, whose
# plain copies it then never pulls in; the rest stays uninstrumented (one
# file to compile, seconds). A read past an array or a traversal stack
# smaller than the tree is deep then stops the check with the line.
LAB_SAN := -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
LAB_SAFE_OBJ := $(BUILD)/lab/student.safe.o $(BUILD)/lab/student_grid.safe.o
$(LAB_SAFE_OBJ): $(BUILD)/lab/%.safe.o: lab/%.c $(FLAGS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(LAB_SAN) $(DEPFLAGS) -c $< -o $@
$(BIN)/lab-safe: $(LAB_SAFE_OBJ) $(BUILD)/lab/lab.o $(BUILD)/lab/check.o $(BUILD)/lab/check_common.o \
                 $(BUILD)/lab/check_step3.o $(BUILD)/lab/check_step5.o $(BUILD)/lab/check_top.o $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $(LAB_SAN) $^ -o $@ $(LDLIBS)

# The header test compiles every header as C and C++ and links a C++
# program against this build's library, with this build's link flags.
$(BUILD)/tests/test_headers.o: ALL_CFLAGS += -DTEST_CC='"$(CC)"' -DTEST_CXX='"$(CXX)"' \
    -DTEST_LIB='"$(LIB)"' -DTEST_LDLIBS='"$(LDLIBS)"'

$(BIN)/run_tests: $(TEST_OBJ) $(LIB)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $(TEST_OBJ) $(LIB) -o $@ $(LDLIBS)

.SECONDARY:

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)

test: all
	./$(BIN)/run_tests $(if $(J),-j $(J)) '$(T)'

report: all
	GRIDBVH_CFLAGS="$(ALL_CFLAGS)" CC="$(CC)" KINDS="$(KINDS)" ACCEL="$(ACCEL)" \
	  SCENES="$(SCENES)" ./experiments/report.sh $(if $(filter 1,$(QUICK)),--quick,)

bench: all
	./experiments/bench.sh

# Tests under ASan + UBSan in a separate build tree, with the same
# instruction set as the product (ARCH), so that the SIMD kernels it runs
# are the ones checked; the wide kernels' helpers not forced inline
# (core/simd.h: minutes of compile time otherwise). The tests that run
# a tool, an experiment or the report (bin/trace, bin/exp_*, bin/mkreport)
# run the product's binaries in bin/: they are built first, so that a fresh
# clone's `make sanitize` needs no `make` before it.
sanitize: $(TOOLS) $(EXP_BINS) $(BIN)/mkreport
	$(MAKE) BUILD=build-san BIN=bin-san OPT=-O1 \
	  CFLAGS="-O1 -g $(ARCH) -DWIDE_NO_FORCE_INLINE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" \
	  LDLIBS="-lm -pthread -fsanitize=address,undefined" bin-san/run_tests
	ASAN_OPTIONS=detect_leaks=1 ./bin-san/run_tests '$(T)'

fuzz:
	$(MAKE) -C tests/fuzz

# The checks of steps other than 5 (which times frames) run bin-lab/lab-safe
# where the compiler can link the sanitizers (asked only by these targets).
ifneq ($(filter lab lab-report,$(MAKECMDGOALS)),)
LAB_HAVE_SAN := $(shell printf 'int main(void){return 0;}\n' | $(CC) $(LAB_SAN) -x c - -o /dev/null 2>/dev/null && echo 1)
endif
LAB_CHECKER = $(if $(and $(LAB_HAVE_SAN),$(filter-out 5,$(STEP))),lab-safe,lab)

# The lab (LAB.md): the student's kind, lab/student.c, made from the starter
# on first use and registered only in this build (build-lab/, bin-lab/).
# make lab STEP=n runs step n's check on it, writing its images to lab/out/.
# The build is quiet (-s): only the compiler's warnings and errors show, so
# the check's report is not buried under link lines.
lab:
	@test -f lab/student.c || { sed -e 's/accel_kind_starter/accel_kind_student/' -e 's/lab_top_starter/lab_top_student/' \
	  -e 's/"starter"/"student"/' -e 's@^ \* starter.c - @ * student.c - @' lab/starter.c > lab/student.c && \
	  echo "lab: made lab/student.c from lab/starter.c: your kind is 'student'"; }
	@test -f lab/student_grid.c || { sed -e 's/accel_kind_grid_starter/accel_kind_student_grid/' \
	  -e 's/"grid_starter"/"student_grid"/' -e 's@^ \* grid_starter.c - @ * student_grid.c - @' \
	  lab/grid_starter.c > lab/student_grid.c && \
	  echo "lab: made lab/student_grid.c from lab/grid_starter.c (the optional grid step, STEP=6)"; }
	@mkdir -p lab/out
	@test -x bin-lab/lab || echo "lab: building bin-lab/ (the first time takes minutes: make -j2 lab uses 2 cores)"
	@$(MAKE) -s --no-print-directory BUILD=build-lab BIN=bin-lab LAB=1 bin-lab/lab bin-lab/trace \
	  bin-lab/run_tests bin-lab/mkreport $(patsubst $(BIN)/%,bin-lab/%,$(EXP_BINS)) \
	  $(if $(LAB_HAVE_SAN),bin-lab/lab-safe)
	@if [ -n "$(STEP)" ]; then ASAN_OPTIONS=detect_leaks=0 ./bin-lab/$(LAB_CHECKER) --step $(STEP) --out lab/out $(if $(filter 5,$(STEP)),&& \
	   { echo "step 5 (last): your kind through the conformance suite (bin-lab/run_tests conformance_student)"; \
	     KINDS=student ./bin-lab/run_tests conformance_student > lab/out/conformance.txt 2>&1 && tail -n 1 lab/out/conformance.txt || \
	     { grep -v '^ *ok ' lab/out/conformance.txt | head -n 40; echo "step 5: not yet (lab/out/conformance.txt)"; exit 1; }; }); \
	 else echo "lab: built bin-lab/ (trace, run_tests, experiments) with your kind 'student'; make lab STEP=1..5 checks a step (optional: 6 a grid, 7 your top level)"; fi

# The study's report with the student's kind beside the project's, into
# lab/out/report/REPORT.md (QUICK=1: the smoke budget, a minute; KINDS=
# student,bvh,grid: only these kinds; the default adds 'student' to every
# experiment's own list).
lab-report: lab
	BIN=bin-lab GRIDBVH_CFLAGS="$(ALL_CFLAGS) -DGRIDBVH_LAB" CC="$(CC)" KINDS="$(KINDS)" \
	  ACCEL="$(if $(ACCEL),$(ACCEL),student)" ./experiments/report.sh --dir lab/out/report $(if $(filter 1,$(QUICK)),--quick,)

clean:
	rm -rf build build-san bin bin-san build-lab bin-lab
