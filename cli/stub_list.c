#include <stdio.h>
#include "commands.h"
int nprfx_cmd_list(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "nprfx list: not implemented yet\n");
    return 2;
}
