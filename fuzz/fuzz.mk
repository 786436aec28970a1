# fuzz.mk -- builds the libFuzzer targets (GNU make).  `make fuzz` in a
# configured build folder runs this file; by hand:
#   make -f SRCDIR/fuzz/fuzz.mk srcdir=SRCDIR builddir=BUILDDIR \
#        [outdir=OUTDIR] LIB_SOURCES="src/base.c ..." DEP_CFLAGS="..." \
#        DEP_LIBS="..."
#
# BUILDDIR is the configured build folder (for config.h); OUTDIR (default
# BUILDDIR) is where the fuzz build goes.  The library's C files are
# compiled again with clang and the fuzzing flags into OUTDIR/fuzz/obj (the
# normal build and its flags are not touched), archived into
# OUTDIR/fuzz/libsoilsim-fuzz.a, and each target fuzz/fuzz_NAME.c is linked
# with libFuzzer's main:
#   OUTDIR/fuzz/fuzz_scene   world XML (ss_scene_load_buffer, + step, export)
#   OUTDIR/fuzz/fuzz_urdf    URDF (ss_urdf_load_buffer + articulated build)
#   OUTDIR/fuzz/fuzz_mesh    meshes (ss_mesh_load on a temporary file)
#   OUTDIR/fuzz/fuzz_checkpoint  checkpoints (ss_checkpoint_load_buffer)

srcdir ?= .
builddir ?= .
outdir ?= $(builddir)
FUZZ_CC ?= clang
# -O1 keeps the runs fast and the stacks readable; no recovery, so every
# undefined-behaviour report is a crash libFuzzer keeps as an artifact
FUZZ_CFLAGS ?= -g -O1 -fno-omit-frame-pointer
# Nothing is recoverable and nothing is suppressed: every report stops the
# target.  FUZZ_UBSAN_EXCLUDE can leave checks out by hand while a report
# is being fixed (e.g. -fno-sanitize=float-cast-overflow)
FUZZ_UBSAN_EXCLUDE ?=
FUZZ_SAN = -fsanitize=address,undefined,float-cast-overflow \
	-fno-sanitize-recover=all $(FUZZ_UBSAN_EXCLUDE)
STD_FLAGS = -std=c11 -Wall -Wextra -Wno-unused-parameter -ffp-contract=off \
	-fno-fast-math
FUZZ_CPPFLAGS = -I$(srcdir)/src -I$(srcdir)/fuzz -I$(builddir) \
	-D_POSIX_C_SOURCE=200809L -DSS_FUZZ_SRCDIR='"$(srcdir)"'

O = $(outdir)/fuzz/obj
LIB_C = $(filter %.c,$(LIB_SOURCES))
LIB_O = $(patsubst %.c,$(O)/%.o,$(LIB_C))
LIB_A = $(outdir)/fuzz/libsoilsim-fuzz.a

NAMES = scene urdf mesh
# the checkpoint target needs the checkpoint reader
ifneq ($(shell grep -l 'ss_checkpoint_load_buffer' $(srcdir)/src/soilsim.h 2>/dev/null),)
NAMES += checkpoint
endif
TARGETS = $(patsubst %,$(outdir)/fuzz/fuzz_%,$(NAMES))

# objects are rebuilt when the compiler or the flags change
FLAGS_NOW = $(FUZZ_CC) $(STD_FLAGS) $(FUZZ_CPPFLAGS) $(DEP_CFLAGS) $(FUZZ_CFLAGS) $(FUZZ_SAN)
FLAGS_STAMP = $(O)/flags
ifneq ($(strip $(file <$(FLAGS_STAMP))),$(strip $(FLAGS_NOW)))
$(shell mkdir -p $(O))
$(file >$(FLAGS_STAMP),$(strip $(FLAGS_NOW)))
endif

all: $(TARGETS)
	@echo "fuzz targets: $(TARGETS)"

$(O)/%.o: $(srcdir)/%.c $(FLAGS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  FUZZCC   $*.c"
	@$(FUZZ_CC) $(STD_FLAGS) $(FUZZ_CPPFLAGS) $(DEP_CFLAGS) $(FUZZ_CFLAGS) \
		$(FUZZ_SAN) -fsanitize=fuzzer-no-link -MMD -MP -c $< -o $@

$(LIB_A): $(LIB_O)
	@rm -f $@
	@echo "  AR       $@"
	@ar rcs $@ $(LIB_O)

$(outdir)/fuzz/fuzz_%: $(O)/fuzz/fuzz_%.o $(O)/fuzz/fuzz_common.o $(LIB_A)
	@echo "  FUZZLD   $@"
	@$(FUZZ_CC) $(FUZZ_CFLAGS) $(FUZZ_SAN) -fsanitize=fuzzer \
		$(O)/fuzz/fuzz_$*.o $(O)/fuzz/fuzz_common.o $(LIB_A) $(DEP_LIBS) -lm -o $@

-include $(LIB_O:.o=.d) $(wildcard $(O)/fuzz/*.d)

.PHONY: all
.SECONDARY:
