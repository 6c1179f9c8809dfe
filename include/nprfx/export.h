/* nprfx — which symbols leave the library.
 *
 * libnprfx is compiled with hidden visibility (-fvisibility=hidden): only the functions declared
 * with NPRFX_API in these headers are exported from libnprfx.so; internal helpers stay inside.
 * With GCC and Clang NPRFX_API gives default visibility, both while the library is built and in
 * the programs that use it. The same objects make libnprfx.a, where it is harmless. A static user
 * may define NPRFX_STATIC (the CMake target nprfx::nprfx_static does) to make it expand to
 * nothing, which changes nothing on ELF platforms. */
#ifndef NPRFX_EXPORT_H
#define NPRFX_EXPORT_H

#if defined(NPRFX_STATIC)
#define NPRFX_API
#elif defined(__GNUC__) || defined(__clang__)
#define NPRFX_API __attribute__((visibility("default")))
#else
#define NPRFX_API
#endif

#endif
