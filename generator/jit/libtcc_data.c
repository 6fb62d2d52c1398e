/* libtcc_data.c - libmechc.so's copies of the three libc variables its libtcc reads (stdout, stderr, environ).
 *
 * Debian ships libtcc only as a static archive of position-independent
 * executable code: linked into a shared object, its PC-relative loads of
 * libc's stdout, stderr and environ cannot be resolved (they would need
 * copy relocations). The Makefile links libmechc.so with a copy of the
 * archive whose references to them are renamed to these, which are
 * local to the library (generator/lib/mechc.map) and set from libc's
 * when it is loaded. Only in the .so's objects (MECHC_SHARED).
 */
#ifdef MECHC_SHARED
#include <stdio.h>
extern char **environ;

extern FILE *libtcc_stdout, *libtcc_stderr;
extern char **libtcc_environ;
FILE *libtcc_stdout, *libtcc_stderr;
char **libtcc_environ;

__attribute__((constructor)) static void libtcc_data_init(void)
{
    libtcc_stdout = stdout;
    libtcc_stderr = stderr;
    libtcc_environ = environ;
}
#endif
