/* Strict parsing of numbers given on the command line (capdem run, capdem
 * analyze/render --snapshot, capdem-bench): the whole argument must be the
 * number, in range; no silent 0 for garbage, no wrap-around. */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "config/config.h"

static void expect_int(const char *opt, const char *s, long long lo, long long hi, const char *why, char *err,
                       size_t errlen)
{
    if (hi == LLONG_MAX) snprintf(err, errlen, "%s %s: %sexpected an integer >= %lld", opt, s, why, lo);
    else snprintf(err, errlen, "%s %s: %sexpected an integer in [%lld, %lld]", opt, s, why, lo, hi);
}

int cd_parse_cli_int(const char *opt, const char *s, long long lo, long long hi, long long *out, char *err,
                     size_t errlen)
{
    char *end;
    if (!s || !*s || isspace((unsigned char)s[0])) {
        expect_int(opt, s ? s : "(missing)", lo, hi, "", err, errlen);
        return -1;
    }
    errno = 0;
    long long v = strtoll(s, &end, 10);
    if (end == s || *end) {
        expect_int(opt, s, lo, hi, "", err, errlen);
        return -1;
    }
    if (errno == ERANGE || v < lo || v > hi) {
        expect_int(opt, s, lo, hi, errno == ERANGE ? "out of range, " : "", err, errlen);
        return -1;
    }
    *out = v;
    return 0;
}

int cd_parse_cli_real(const char *opt, const char *s, double lo, double hi, double *out, char *err, size_t errlen)
{
    char *end;
    errno = 0;
    double v = s && *s && !isspace((unsigned char)s[0]) ? strtod(s, &end) : NAN;
    if (!s || !*s || isspace((unsigned char)s[0]) || end == s || *end || !isfinite(v) || errno == ERANGE || v < lo ||
        v > hi) {
        if (hi >= HUGE_VAL && lo <= -HUGE_VAL)
            snprintf(err, errlen, "%s %s: expected a finite number", opt, s ? s : "(missing)");
        else if (hi >= HUGE_VAL) snprintf(err, errlen, "%s %s: expected a number >= %g", opt, s ? s : "(missing)", lo);
        else snprintf(err, errlen, "%s %s: expected a number in [%g, %g]", opt, s ? s : "(missing)", lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}
