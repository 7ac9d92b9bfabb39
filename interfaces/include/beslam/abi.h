/* BE-SLAM plugin ABI: versions, status codes, host callbacks, configuration schema, plugin descriptor.
 *
 * The contract between the host (platform/) and every plugin library. C11, no dependencies, fixed-width
 * fields only. Rules (docs/abi.md):
 *  - A library exports two C symbols: beslam_plugin_abi_version() and beslam_plugin_list(). The host
 *    reads the first without touching anything else and refuses a different major version.
 *  - Every struct that may grow starts with uint32_t struct_size. A minor version only appends fields;
 *    the host zero-fills what an older plugin does not know. Nothing is ever reordered or removed; a
 *    breaking change to a kind gets a new table (beslam_detector_v2 ...).
 *  - Inputs are borrowed for the duration of one call. Outputs go into host buffers, or into memory the
 *    plugin instance owns until its next call or destroy.
 *  - Every call returns a beslam_status; details go through the host's log callback. No exception or
 *    longjmp crosses this boundary.
 */
#ifndef BESLAM_ABI_H
#define BESLAM_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define BESLAM_ABI_VERSION_MAJOR 1
#define BESLAM_ABI_VERSION_MINOR 7
/* (major << 16) | minor, as returned by beslam_plugin_abi_version(). */
#define BESLAM_ABI_VERSION ((uint32_t)((BESLAM_ABI_VERSION_MAJOR << 16) | BESLAM_ABI_VERSION_MINOR))

#if defined(_WIN32)
#define BESLAM_EXPORT __declspec(dllexport)
#else
#define BESLAM_EXPORT __attribute__((visibility("default")))
#endif

/* ---- Status codes (int32) ---- */
typedef int32_t beslam_status;
#define BESLAM_OK 0
#define BESLAM_ERROR_INVALID_ARGUMENT 1 /* a null pointer, a bad size, a view of the wrong format */
#define BESLAM_ERROR_INVALID_CONFIG 2   /* a configuration value the plugin cannot use */
#define BESLAM_ERROR_RUNTIME 3          /* the call failed on its input (missing file, NaN, ...) */
#define BESLAM_ERROR_OUT_OF_MEMORY 4
#define BESLAM_ERROR_UNSUPPORTED 5 /* the plugin does not offer this call */
#define BESLAM_ERROR_INTERNAL 6    /* a bug: an unexpected exception inside the plugin */

/* ---- Plugin kinds (int32) ---- */
#define BESLAM_KIND_DETECTOR 1
#define BESLAM_KIND_MOTION_CHECKER 2
#define BESLAM_KIND_MASK_GENERATOR 3
#define BESLAM_KIND_RECONSTRUCTOR 4
#define BESLAM_KIND_BACKEND 5

/* ---- Log levels (int32) ---- */
#define BESLAM_LOG_DEBUG 0
#define BESLAM_LOG_INFO 1
#define BESLAM_LOG_WARNING 2
#define BESLAM_LOG_ERROR 3

/* Services the host lends to a plugin instance for its whole life. */
typedef struct beslam_host {
  uint32_t struct_size;
  uint32_t abi_version; /* the host's BESLAM_ABI_VERSION */
  void* user_data;      /* pass back to every callback */
  /* Log a message. An ERROR logged right before a call returns non-OK becomes that call's error text. */
  void (*log)(void* user_data, int32_t level, const char* plugin_id, const char* message);
} beslam_host;

/* ---- Configuration schema ---- */
#define BESLAM_CONFIG_BOOL 1
#define BESLAM_CONFIG_INT 2
#define BESLAM_CONFIG_DOUBLE 3
#define BESLAM_CONFIG_STRING 4
#define BESLAM_CONFIG_PATH 5 /* a string the host resolves against the pipeline file's folder */
#define BESLAM_CONFIG_DOUBLE_LIST 6

/* One key a plugin accepts. The host validates pipeline YAML against these before create(). */
typedef struct beslam_config_field {
  const char* key;           /* "fast_threshold" */
  int32_t type;              /* BESLAM_CONFIG_* */
  int32_t required;          /* 1: no default, the pipeline must set it */
  const char* default_value; /* YAML text of the default ("20", "true", "[0.5, 1.0]"); NULL if required */
  double min_value;          /* numbers (and each list element): inclusive range; ignored if min > max */
  double max_value;
  const char* choices; /* strings: "a|b|c" to restrict the value, or NULL */
  const char* doc;     /* one line for `beslam plugins` */
} beslam_config_field;

/* One resolved configuration value, handed to create(). Every schema key is present (defaults filled). */
typedef struct beslam_config_value {
  const char* key;
  int32_t type;
  int32_t reserved;
  double number;      /* BOOL (0/1), INT, DOUBLE */
  const char* text;   /* STRING, PATH (absolute after resolution) */
  const double* list; /* DOUBLE_LIST */
  uint64_t list_size;
} beslam_config_value;

struct beslam_create_info; /* data.h: camera, extrinsics, configuration */

/* ---- The plugin descriptor: one per plugin; a library may hold several ---- */
typedef struct beslam_plugin_descriptor {
  uint32_t struct_size;
  uint32_t abi_version;    /* BESLAM_ABI_VERSION the plugin was built against */
  const char* id;          /* stable, unique, [a-z0-9_]+: "backend_orb" */
  const char* name;        /* display name */
  const char* description; /* one line */
  int32_t kind;            /* BESLAM_KIND_* */
  uint32_t version_major;  /* the plugin's own version */
  uint32_t version_minor;
  uint32_t version_patch;
  const beslam_config_field* config_fields;
  uint32_t config_field_count;
  uint32_t config_field_size; /* sizeof(beslam_config_field) as the plugin knows it */
  /* Make an instance. On failure return non-OK and log the reason through info->host. */
  beslam_status (*create)(const struct beslam_create_info* info, void** out_instance);
  void (*destroy)(void* instance);
  const void* functions; /* the kind's table (beslam_detector_v1 ...); starts with uint32_t struct_size */
} beslam_plugin_descriptor;

/* Exported entry points (names are part of the ABI). */
#define BESLAM_ABI_VERSION_SYMBOL "beslam_plugin_abi_version"
#define BESLAM_PLUGIN_LIST_SYMBOL "beslam_plugin_list"
typedef uint32_t (*beslam_plugin_abi_version_fn)(void);
/* Returns an array of *out_count descriptor pointers that stay valid while the library is loaded. */
typedef beslam_status (*beslam_plugin_list_fn)(const beslam_plugin_descriptor* const** out_descriptors,
                                               uint32_t* out_count);

#ifdef __cplusplus
}
#endif

#endif /* BESLAM_ABI_H */
