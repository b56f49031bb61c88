/* Command-line parsing helpers: strict numbers, WxH sizes, one-line usage errors. */
#ifndef EVR_CLI_OPTIONS_H
#define EVR_CLI_OPTIONS_H

#include "evray.h"

/* Each returns 0 and prints "evray: error: ..." when the text is not a valid value. */
int opt_double(const char *opt, const char *text, double *out);
int opt_float(const char *opt, const char *text, float *out);
int opt_int(const char *opt, const char *text, int *out);
int opt_u64(const char *opt, const char *text, uint64_t *out);
int opt_size(const char *opt, const char *text, int *w, int *h);
int opt_formats(const char *text, int *formats);

/* Splits "--name=value" or "--name value"; returns the value or NULL (after an error message)
 * when it is missing. *i is advanced past a separate value. */
const char *opt_value(int argc, char **argv, int *i, const char *name);
/* 1 when argv[i] is --name or --name=... */
int opt_is(const char *arg, const char *name);

void cli_error(const char *fmt, ...);

/* The scene file at path, else the built-in scene demo (its variant demo_seed:
 * evr_demo_glb_variant), with --animation's choice (NULL: the
 * default rule), --strict's (every import warning an error) and --allow-external-files' (files
 * outside the scene's folder may be read); prints the loader's notice
 * unless quiet, and the scene's warnings (evr_scene_warnings) always, on stderr. NULL (after the
 * error message) when it cannot be loaded, a clip the file does not have included. */
evr_scene *cli_load_scene(const char *path, const char *demo, uint64_t demo_seed,
                          const char *animation, int strict, int allow_external, int quiet);
/* cli_load_scene's quiet for a caller that prints the notice and the warnings itself */
#define CLI_LOAD_DESCRIBED (-1)
/* --animation NAME|INDEX|all at argv[*i]: 1 (its value in *animation, *i past it), 0 when
 * argv[*i] is another argument, -1 after an error message. */
int cli_is_animation_option(int argc, char **argv, int *i, const char **animation);

/* A run with global illumination whose photon buffer dropped more than 1% of the photons that
 * reached it: one warning line saying how many and what keeps them. */
void cli_warn_photon_drops(const evr_stats *s);
/* The help line of --animation, for every command that loads a scene. */
#define CLI_ANIMATION_HELP                                                                     \
    "  --animation CLIP           animation clips that play: a clip's name or 0-based index\n" \
    "                             alone, or all (default: clips that animate disjoint nodes\n" \
    "                             play together, the later of two sharing a node does not;\n"  \
    "                             evray info SCENE lists them)\n"

/* The help line of --strict, for the commands that parse it themselves (info, still). */
#define CLI_STRICT_HELP                                                                    \
    "  --strict                   fail on anything evray would otherwise warn about and\n" \
    "                             leave out of the file (a texture it cannot find or\n"    \
    "                             decode, an extension it does not render, ...)\n"
#define CLI_EXTERNAL_HELP                                                                 \
    "  --allow-external-files     let the scene read files outside its own folder (by\n"  \
    "                             default a buffer or image named by an absolute path,\n" \
    "                             by '..' or through a link out of it is refused)\n"

#endif
