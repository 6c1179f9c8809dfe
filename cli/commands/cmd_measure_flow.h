/* nprfx CLI — nprfx measure flow (cmd_measure_flow.c). */
#ifndef NPRFX_CLI_CMD_MEASURE_FLOW_H
#define NPRFX_CLI_CMD_MEASURE_FLOW_H

/* nprfx measure flow: argv[0] is "flow". */
int cli_cmd_measure_flow(int argc, char **argv);

#endif
