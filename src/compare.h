/* Accuracy of one event stream against a reference; declared in evray_experimental.h (the
 * program's interface to it). */
#ifndef EVR_COMPARE_H
#define EVR_COMPARE_H

#include "evray_experimental.h"

#endif
