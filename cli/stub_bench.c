#include <stdio.h>
#include "commands.h"
int nprfx_cmd_bench(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "nprfx bench: not implemented yet\n");
    return 2;
}
