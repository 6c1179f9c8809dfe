#include <stdio.h>
#include "commands.h"
int nprfx_cmd_run(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "nprfx run: not implemented yet\n");
    return 2;
}
