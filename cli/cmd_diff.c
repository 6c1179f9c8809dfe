/* nprfx diff — placeholder until implemented. */
#include <stdio.h>

#include "commands.h"

int nprfx_cmd_diff(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "nprfx diff: not implemented yet\n");
    return 2;
}
