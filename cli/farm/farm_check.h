/* nprfx farm check (farm_check.c): what a job's last step verifies once every chunk has ended. */
#ifndef NPRFX_CLI_FARM_CHECK_H
#define NPRFX_CLI_FARM_CHECK_H

/* nprfx farm check (argv[0] is "check"). */
int farm_check(int argc, char **argv);

#endif
