# sources.mk - which files make up the library, shared by the top-level
# Makefile and tests/fuzz/Makefile (set ROOT to the repository, with a
# trailing slash, before including; empty at the top level).
#
# Every top-level folder with .c files other than NOT_BACKENDS is a backend
# whose files go into the library: a new backend is a new folder plus its
# line in accel/core/registry.c, nothing else.
NOT_BACKENDS := accel experiments tests tools lab build build-san bin bin-san build-nocount bin-nocount
BACKENDS     := $(filter-out $(NOT_BACKENDS),$(patsubst $(ROOT)%/,%,$(sort $(dir $(wildcard $(ROOT)*/*.c)))))
ACCEL_LAYERS := core scene rays measure image cli
CORE_SRC     := $(foreach l,$(ACCEL_LAYERS),$(wildcard $(ROOT)accel/$(l)/*.c))
# A backend's sources are its folder's .c files and those of its subfolders
# (bvh/wide/), one level down.
BACKEND_SRC  := $(foreach d,$(BACKENDS),$(wildcard $(ROOT)$(d)/*.c $(ROOT)$(d)/*/*.c))
# The slowest units to compile (bvh/wide/'s kernel tables, 4-15 s of CPU each) come
# first, so that a parallel build overlaps them with the many small ones
# instead of finishing on them. They are also the units the Makefile
# compiles a second time for AVX-512: k<digit>_*.c in a backend's
# subfolder (bvh/wide/) or in the backend's own folder (instanced/k8_trace.c).
SLOW_SRC     := $(foreach d,$(BACKENDS),$(wildcard $(ROOT)$(d)/*/k[0-9]_*.c $(ROOT)$(d)/k[0-9]_*.c))
LIB_SRC      := $(SLOW_SRC) $(CORE_SRC) $(filter-out $(SLOW_SRC),$(BACKEND_SRC))
LOADER_SRC   := $(wildcard $(ROOT)accel/scene/load_*.c)
