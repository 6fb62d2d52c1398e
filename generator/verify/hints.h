/* hints.h - the check's verdict, and what mistake a failed comparison looks like. */
#ifndef MECHC_VERIFY_HINTS_H
#define MECHC_VERIFY_HINTS_H

#include "checker.h"

/* The verdict, and a hint for every item above its tolerance. */
void check_diagnose(Checker *c);

#endif
