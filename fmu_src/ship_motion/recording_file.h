/* The ship-motion FMU's recording file: where it is (absolute, or relative to the resources folder
 * that fmi2Instantiate's fmuResourceLocation names as a file: URI, fmi3InstantiateCoSimulation's
 * resourcePath as a path) and its bytes. No FMI here. */
#ifndef SHIP_RECORDING_FILE_H
#define SHIP_RECORDING_FILE_H

#include <stddef.h>

/* The resources folder of a file: URI ("file:///C:/a%20b/resources", "file://localhost/x",
 * "file:/x"), percent-decoded, without a trailing '/'; NULL when the location is NULL or not a local
 * file: URI, or when out of memory. Free it. */
char* recording_resources_folder(const char* resource_location);

/* The resources folder of FMI 3.0's resourcePath (a path, with or without a trailing separator), a
 * copy without the trailing separator; NULL when the path is NULL or empty, or when out of memory.
 * Free it. */
char* recording_resources_folder_of_path(const char* resource_path);

/* The path of `file`: itself when absolute, else resources/file. NULL, with the reason in `message`,
 * for an empty name, a relative one without a resources folder, or out of memory. Free it. */
char* recording_path(const char* resources, const char* file, char* message, size_t size);

/* The whole file (free it) and its length; NULL with the reason in `message` (naming `path`). */
char* recording_read(const char* path, size_t* length, char* message, size_t size);

#endif
