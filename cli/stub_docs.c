#include <stdio.h>
#include "commands.h"
int nprfx_cmd_docs(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "nprfx docs: not implemented yet\n");
    return 2;
}
