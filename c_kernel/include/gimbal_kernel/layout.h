/* The kernel's structs, each written once as a list of fields: the list makes the C declaration
 * (GIMBAL_STRUCT) and the rows of the layout table that Python reads to build its ctypes view
 * (layout.c: name, offset, kind, count), so no layout or size is copied into Python.
 *
 * A list is a macro taking two macros, FIELD(c_type, name, kind) and ARRAY(c_type, name, kind,
 * count). kind is what Python makes of the field: double, long, int, pointer (any pointer, function
 * pointers included), or the name of another listed struct (nested). */
#ifndef GIMBAL_KERNEL_LAYOUT_H
#define GIMBAL_KERNEL_LAYOUT_H

#define GIMBAL_DECLARE_FIELD(c_type, name, kind) c_type name;
#define GIMBAL_DECLARE_ARRAY(c_type, name, kind, count) c_type name[count];
#define GIMBAL_STRUCT(Name, FIELDS) \
    typedef struct Name {           \
        FIELDS(GIMBAL_DECLARE_FIELD, GIMBAL_DECLARE_ARRAY)  \
    } Name;

#ifdef __cplusplus
extern "C" {
#endif

/* Row `index` of the layout table (0 .. gimbal_layout_field_count() - 1): the struct, the field, its
 * byte offset, its kind and its element count (1 for a plain field). 0 when index is out of range. */
int gimbal_layout_field(long index, const char** structure, const char** field, long* offset, const char** kind,
                        long* count);
long gimbal_layout_field_count(void);
/* sizeof the named struct, or -1 for a name the table does not list. */
long gimbal_layout_size(const char* structure);

#ifdef __cplusplus
}
#endif
#endif
