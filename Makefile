# gridbvh - see README.md.
#   make            optimized library, tools and experiments (bin/)
#   make test       the test suite (T=word: tests whose name contains it;
#                   KINDS=grid,bvh: only these accelerator kinds)
#   make report     runs every experiment and rewrites REPORT.md (QUICK=1: smoke run)
#   make sanitize   the test suite under AddressSanitizer + UBSan
#   make fuzz       libFuzzer targets for the loaders (clang)
CC      ?= cc
ARCH    ?= -march=native
OPT     ?= -O3
CFLAGS  ?= $(OPT) $(ARCH) -g
# Flags every build needs, kept apart so that `make CFLAGS=...` cannot drop them.
BASE_CFLAGS := -std=c11 -D_GNU_SOURCE -Wall -Wextra -pthread -Iaccel -I.
ALL_CFLAGS = $(BASE_CFLAGS) $(CFLAGS)
LDLIBS  += -lm -pthread
BUILD   ?= build
BIN     ?= bin

# Every top-level folder with .c files other than these is a backend whose
# files go into the library: a new backend is a new folder plus its line in
# accel/registry.c, nothing else.
NOT_BACKENDS := accel experiments tests tools build build-san bin bin-san
BACKENDS := $(filter-out $(NOT_BACKENDS),$(patsubst %/,%,$(sort $(dir $(wildcard */*.c)))))
LIB_SRC  := $(wildcard accel/*.c) $(foreach d,$(BACKENDS),$(wildcard $(d)/*.c))
LIB_OBJ  := $(LIB_SRC:%.c=$(BUILD)/%.o)
LIB      := $(BUILD)/libgridbvh.a
HDRS     := $(wildcard accel/*.h) $(foreach d,$(BACKENDS),$(wildcard $(d)/*.h)) $(wildcard experiments/*.h) $(wildcard tests/*.h)

TOOLS    := $(patsubst tools/%.c,$(BIN)/%,$(wildcard tools/*.c))
EXP_LIB  := $(filter-out experiments/exp_%.c,$(wildcard experiments/*.c))
EXP_BINS := $(patsubst experiments/%.c,$(BIN)/%,$(wildcard experiments/exp_*.c))
TEST_SRC := $(wildcard tests/*.c)

.PHONY: all test report sanitize fuzz clean bench
all: $(TOOLS) $(EXP_BINS) $(BIN)/run_tests

$(BUILD)/%.o: %.c $(HDRS)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(LIB): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BIN)/%: tools/%.c $(LIB) $(HDRS)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $< $(LIB) -o $@ $(LDLIBS)

$(BIN)/exp_%: experiments/exp_%.c $(EXP_LIB) $(LIB) $(HDRS)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $< $(EXP_LIB) $(LIB) -o $@ $(LDLIBS)

$(BIN)/run_tests: $(TEST_SRC) $(LIB) $(HDRS)
	@mkdir -p $(BIN)
	$(CC) $(ALL_CFLAGS) $(TEST_SRC) $(LIB) -o $@ $(LDLIBS)

test: all
	./$(BIN)/run_tests $(T)

report: all
	GRIDBVH_CFLAGS="$(ALL_CFLAGS)" CC="$(CC)" ./experiments/report.sh $(if $(QUICK),--quick,)

bench: all
	./experiments/bench.sh

# Tests under ASan + UBSan in a separate build tree.
sanitize:
	$(MAKE) BUILD=build-san BIN=bin-san OPT=-O1 \
	  CFLAGS="-O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" \
	  LDLIBS="-lm -pthread -fsanitize=address,undefined" bin-san/run_tests
	ASAN_OPTIONS=detect_leaks=1 ./bin-san/run_tests $(T)

fuzz:
	$(MAKE) -C tests/fuzz

clean:
	rm -rf build build-san bin bin-san
