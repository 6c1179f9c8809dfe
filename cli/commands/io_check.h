/* nprfx CLI — nprfx info --io-test damaged (io_check.c). */
#ifndef NPRFX_CLI_IO_CHECK_H
#define NPRFX_CLI_IO_CHECK_H

/* nprfx info --io-test damaged LIST: one verdict a file. */
int nprfx_io_check_damaged(const char *list);

#endif
