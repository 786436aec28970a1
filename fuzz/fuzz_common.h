/* fuzz_common.h -- helpers shared by the libFuzzer targets in fuzz/.
 *
 * SS_FUZZ_SRCDIR (a string, set by fuzz/fuzz.mk) is the absolute source
 * tree: the targets name their in-memory inputs as files there, so that
 * relative paths and [THIS_DIR] in a fuzzed scene or URDF reach the real
 * assets (assets/plate_arm, tests/data/urdf/meshes) as they would on disk. */
#ifndef SS_FUZZ_COMMON_H
#define SS_FUZZ_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifndef SS_FUZZ_SRCDIR
#define SS_FUZZ_SRCDIR "."
#endif

/* A private temporary folder for this process (created on first use,
 * removed with everything in it at exit); NULL if it cannot be made. */
const char *ss_fuzz_tmpdir(void);

/* Write len bytes to path (created or truncated); 0 on success. */
int ss_fuzz_write_file(const char *path, const uint8_t *data, size_t len);

/* The libFuzzer entry point each target defines. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif /* SS_FUZZ_COMMON_H */
