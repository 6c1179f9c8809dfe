#include <stdio.h>
#include "commands.h"
int nprfx_cmd_help(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "nprfx help: not implemented yet\n");
    return 2;
}
