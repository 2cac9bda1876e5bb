/* `capdem run` of a config with solver: mpm (docs/mpm.md). */
#ifndef CD_MPM_RUN_H
#define CD_MPM_RUN_H
#include "config/config.h"
#include "core/run.h"

/* Runs cfg (already read, output path resolved and checked); returns the
 * exit status (0 done, 2 bad input, 3 blew up, 1 other failures). */
int cd_mpm_run(const cd_run_options *opt, cd_config *cfg);

#endif
