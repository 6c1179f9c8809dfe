/* nprfx synth — placeholder until implemented. */
#include <stdio.h>

#include "commands.h"

int nprfx_cmd_synth(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "nprfx synth: not implemented yet\n");
    return 2;
}
