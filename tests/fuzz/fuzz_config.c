/* libFuzzer target: the config loader (src/config*.c) on arbitrary bytes.
 * Every input must either load (and then compare with itself, key by key,
 * without a refused key, as a resume of an unchanged config does) or be
 * refused with a message; anything else (a crash, a sanitizer finding, an
 * empty message, a hang) is a finding.  docs/testing.md, "Sanitizers and
 * fuzzing", says how to run it. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "config/config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* cd_config_parse reads a C string, as cd_config_load hands it the
     * file: the input up to its first NUL */
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = 0;
    cd_config c;
    char err[2048] = "";
    if (cd_config_parse(text, "fuzz.yaml", &c, err, sizeof err) == 0) {
        static char refused[16384], accepted[16384];
        if (cd_config_resume_diff(&c, &c, NULL, 0, refused, sizeof refused, accepted, sizeof accepted) != 0) {
            fprintf(stderr, "a config differs from itself:\n%s", refused);
            abort();
        }
        cd_config_free(&c);
    } else if (!err[0] || !strstr(err, "fuzz.yaml")) {
        fprintf(stderr, "refused without a message naming the file: \"%s\"\n", err);
        abort();
    }
    free(text);
    return 0;
}
