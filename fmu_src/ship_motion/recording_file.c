#include "recording_file.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Files above this are refused: a recording is text, a few megabytes at most. */
static const long kMaximumBytes = 1L << 30;

static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static int has_drive_letter(const char* path) {
    return isalpha((unsigned char)path[0]) && path[1] == ':' && (path[2] == '/' || path[2] == '\\' || path[2] == '\0');
}

/* The path of a file: URI, its authority (empty or localhost) dropped; NULL for another host's. */
static const char* uri_path(const char* resource_location) {
    if (resource_location == NULL || strncmp(resource_location, "file:", 5) != 0) return NULL;
    const char* path = resource_location + 5;
    if (strncmp(path, "//", 2) != 0) return path;
    path += 2;
    if (strncmp(path, "localhost", 9) == 0) path += 9;
    return *path == '/' ? path : NULL;
}

/* `path` with its %XX escapes decoded into `folder` (as long as `path` at least); the decoded length. */
static size_t percent_decoded(const char* path, char* folder) {
    size_t j = 0;
    for (size_t i = 0; path[i] != '\0'; ++i) {
        if (path[i] == '%' && hex_value(path[i + 1]) >= 0 && hex_value(path[i + 2]) >= 0) {
            folder[j++] = (char)(16 * hex_value(path[i + 1]) + hex_value(path[i + 2]));
            i += 2;
        } else {
            folder[j++] = path[i];
        }
    }
    folder[j] = '\0';
    return j;
}

char* recording_resources_folder(const char* resource_location) {
    const char* path = uri_path(resource_location);
    if (path == NULL) return NULL;
    char* folder = malloc(strlen(path) + 1);
    if (folder == NULL) return NULL;
    size_t j = percent_decoded(path, folder);
    if (folder[0] == '/' && has_drive_letter(folder + 1)) memmove(folder, folder + 1, j--); /* /C:/x is C:/x */
    while (j > 1 && (folder[j - 1] == '/' || folder[j - 1] == '\\')) folder[--j] = '\0';
    return folder;
}

char* recording_resources_folder_of_path(const char* resource_path) {
    if (resource_path == NULL || resource_path[0] == '\0') return NULL;
    size_t length = strlen(resource_path);
    char* folder = malloc(length + 1);
    if (folder == NULL) return NULL;
    memcpy(folder, resource_path, length + 1);
    while (length > 1 && (folder[length - 1] == '/' || folder[length - 1] == '\\')) folder[--length] = '\0';
    return folder;
}

static int is_absolute(const char* path) {
    return path[0] == '/' || path[0] == '\\' || has_drive_letter(path);
}

char* recording_path(const char* resources, const char* file, char* message, size_t size) {
    if (file[0] == '\0') {
        snprintf(message, size, "recording_file is empty: name the recording (absolute, or relative to the resources folder)");
        return NULL;
    }
    if (!is_absolute(file) && resources == NULL) {
        snprintf(message, size,
                 "recording_file '%s' is relative, but fmi2Instantiate's fmuResourceLocation gave no local resources folder",
                 file);
        return NULL;
    }
    const size_t length = is_absolute(file) ? strlen(file) : strlen(resources) + 1 + strlen(file);
    char* path = malloc(length + 1);
    if (path == NULL) {
        snprintf(message, size, "out of memory for the recording's path");
        return NULL;
    }
    if (is_absolute(file))
        strcpy(path, file);
    else
        snprintf(path, length + 1, "%s/%s", resources, file);
    return path;
}

char* recording_read(const char* path, size_t* length, char* message, size_t size) {
    FILE* file = fopen(path, "rb");
    if (file == NULL) {
        snprintf(message, size, "recorded motion %s: cannot read it: %s", path, strerror(errno));
        return NULL;
    }
    char* text = NULL;
    size_t used = 0, capacity = 0;
    for (;;) {
        if (used == capacity) {
            capacity = capacity == 0 ? 65536 : 2 * capacity;
            char* grown = capacity > (size_t)kMaximumBytes ? NULL : realloc(text, capacity);
            if (grown == NULL) {
                snprintf(message, size, "recorded motion %s: %s", path,
                         capacity > (size_t)kMaximumBytes ? "larger than 1 GiB, not a recording" : "out of memory");
                free(text);
                fclose(file);
                return NULL;
            }
            text = grown;
        }
        errno = 0;
        const size_t got = fread(text + used, 1, capacity - used, file);
        used += got;
        if (got == 0) break;
    }
    const int failed = ferror(file);
    const int reason = errno; /* fread's: a directory opens, but cannot be read */
    fclose(file);
    if (failed) {
        snprintf(message, size, "recorded motion %s: cannot read it: %s", path,
                 reason != 0 ? strerror(reason) : "a read error");
        free(text);
        return NULL;
    }
    *length = used;
    return text;
}
