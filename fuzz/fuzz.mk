# fuzz.mk -- builds the libFuzzer targets (GNU make).  `make fuzz` in a
# configured build folder runs this file; by hand:
#   make -f SRCDIR/fuzz/fuzz.mk srcdir=SRCDIR builddir=BUILDDIR \
#        LIB_SOURCES="src/base.c ..." DEP_CFLAGS="..." DEP_LIBS="..."
#
# The library's C files are compiled again with clang and the fuzzing
# flags into BUILDDIR/fuzz/obj (the normal build and its flags are not
# touched), archived into BUILDDIR/fuzz/libsoilsim-fuzz.a, and each target
# fuzz/fuzz_NAME.c is linked with libFuzzer's main:
#   BUILDDIR/fuzz/fuzz_scene   world XML (ss_scene_load_buffer, + step, export)
#   BUILDDIR/fuzz/fuzz_urdf    URDF (ss_urdf_load_buffer + articulated build)
#   BUILDDIR/fuzz/fuzz_mesh    meshes (ss_mesh_load on a temporary file)
#   BUILDDIR/fuzz/fuzz_checkpoint  checkpoints (ss_checkpoint_load_buffer),
#                              built once src/checkpoint.c provides it

srcdir ?= .
builddir ?= .
FUZZ_CC ?= clang
# -O1 keeps the runs fast and the stacks readable; no recovery, so every
# undefined-behaviour report is a crash libFuzzer keeps as an artifact
FUZZ_CFLAGS ?= -g -O1 -fno-omit-frame-pointer
# Three checks stay recoverable so that fuzz/ubsan.supp can suppress the
# known reports listed there (and only those); FUZZ_UBSAN_EXCLUDE can
# leave checks out altogether (e.g. -fno-sanitize=nonnull-attribute)
FUZZ_UBSAN_EXCLUDE ?=
FUZZ_SAN = -fsanitize=address,undefined -fno-sanitize-recover=all \
	-fsanitize-recover=nonnull-attribute,pointer-overflow,float-cast-overflow $(FUZZ_UBSAN_EXCLUDE)
STD_FLAGS = -std=c11 -Wall -Wextra -Wno-unused-parameter -ffp-contract=off \
	-fno-fast-math
FUZZ_CPPFLAGS = -I$(srcdir)/src -I$(srcdir)/fuzz -I$(builddir) \
	-D_POSIX_C_SOURCE=200809L -DSS_FUZZ_SRCDIR='"$(srcdir)"'

O = $(builddir)/fuzz/obj
LIB_C = $(filter %.c,$(LIB_SOURCES))
LIB_O = $(patsubst %.c,$(O)/%.o,$(LIB_C))
LIB_A = $(builddir)/fuzz/libsoilsim-fuzz.a

NAMES = scene urdf mesh
# the checkpoint reader is being written; its target joins when it exists
ifneq ($(shell grep -l 'ss_checkpoint_load_buffer' $(srcdir)/src/soilsim.h 2>/dev/null),)
NAMES += checkpoint
endif
TARGETS = $(patsubst %,$(builddir)/fuzz/fuzz_%,$(NAMES))

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

$(builddir)/fuzz/fuzz_%: $(O)/fuzz/fuzz_%.o $(O)/fuzz/fuzz_common.o $(LIB_A)
	@echo "  FUZZLD   $@"
	@$(FUZZ_CC) $(FUZZ_CFLAGS) $(FUZZ_SAN) -fsanitize=fuzzer \
		$(O)/fuzz/fuzz_$*.o $(O)/fuzz/fuzz_common.o $(LIB_A) $(DEP_LIBS) -lm -o $@

-include $(LIB_O:.o=.d) $(wildcard $(O)/fuzz/*.d)

.PHONY: all
.SECONDARY:
