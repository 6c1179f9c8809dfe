/* Descriptor helpers: defaults, parsing and checking values, output description. */
#include "nprfx/node.h"
