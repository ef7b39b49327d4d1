/* Constant tables in program memory. avr-gcc's named address space __flash (GNU C) keeps a
   table out of the ATmega328P's 2 KB of RAM and reads it with LPM; other compilers read the
   same declaration from ordinary read-only memory. No MCU header is needed for either. */
#ifndef HFW_FLASH_H
#define HFW_FLASH_H

#ifdef __FLASH
#define HFW_FLASH __flash
#else
#define HFW_FLASH
#endif

#endif
