/* The version of clwhitted (--version, image metadata). */
#ifndef CW_VERSION_H
#define CW_VERSION_H

#define CW_VERSION "0.1.0"

#endif
