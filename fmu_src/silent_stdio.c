/* The FMU never writes to the host's stdout or stderr. The bundled SUNDIALS does when it cannot
 * report through an instance (CVodeCreate out of memory prints "[CVODE ERROR] CVodeCreate"), so the
 * link wraps its stdio calls (-Wl,--wrap=..., fmu_src/CMakeLists.txt): output to stdout and stderr is
 * dropped, other streams pass through. What matters is reported through the FMI logger anyway. */
#include <stdarg.h>
#include <stdio.h>

int __real_fputc(int character, FILE* stream);
size_t __real_fwrite(const void* data, size_t size, size_t count, FILE* stream);
int __real_fputs(const char* text, FILE* stream);
int __real_vfprintf(FILE* stream, const char* format, va_list args);

static int is_console(FILE* stream) { return stream == stdout || stream == stderr; }

int __wrap_fprintf(FILE* stream, const char* format, ...) {
    if (is_console(stream)) return 0;
    va_list args;
    va_start(args, format);
    const int written = __real_vfprintf(stream, format, args);
    va_end(args);
    return written;
}

int __wrap_vfprintf(FILE* stream, const char* format, va_list args) {
    return is_console(stream) ? 0 : __real_vfprintf(stream, format, args);
}

int __wrap_printf(const char* format, ...) {
    (void)format;
    return 0;
}

int __wrap_puts(const char* text) {
    (void)text;
    return 0;
}

int __wrap_putchar(int character) { return character; }

int __wrap_fputc(int character, FILE* stream) { return is_console(stream) ? character : __real_fputc(character, stream); }

size_t __wrap_fwrite(const void* data, size_t size, size_t count, FILE* stream) {
    return is_console(stream) ? count : __real_fwrite(data, size, count, stream);
}

int __wrap_fputs(const char* text, FILE* stream) { return is_console(stream) ? 0 : __real_fputs(text, stream); }
