/* What startup.c gives the image: text output and the end of the run. */
#ifndef MCU_C_STARTUP_H
#define MCU_C_STARTUP_H

/* Writes the NUL-terminated `s` to QEMU's standard output. */
void put(const char *s);
/* Ends the QEMU run with exit status 0 when `ok`, 1 otherwise. */
void exit_qemu(int ok) __attribute__((noreturn));

#endif
