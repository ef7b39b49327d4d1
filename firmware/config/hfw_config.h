/* The board's configuration: firmware/config/hapkit.h unless the build names another header
   (cmake -DHAPTICD_FIRMWARE_CONFIG=/path/to/mine.h). */
#ifndef HFW_CONFIG_H
#define HFW_CONFIG_H

#ifdef HFW_CONFIG
#include HFW_CONFIG
#else
#include "hapkit.h"
#endif

#endif
