/* nprfx info — placeholder until implemented. */
#include <stdio.h>

#include "commands.h"

int nprfx_cmd_info(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "nprfx info: not implemented yet\n");
    return 2;
}
