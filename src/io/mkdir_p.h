/* Creating a folder and its parents. */
#ifndef EVR_IO_MKDIR_P_H
#define EVR_IO_MKDIR_P_H

/* mkdir -p: 0 on success (also when it exists), -1 with errno set. */
int evr_mkdir_p(const char *path);

#endif
