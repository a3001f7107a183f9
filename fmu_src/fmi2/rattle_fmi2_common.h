/*
 * rattle_fmi2_common.h - what both FMI 2.0 layers do the same way, written once: the status
 * shim of the pythonfmu FMUs (rattle_fmi_shim.c) and the FMI 2.0 face of the native FMUs
 * (fmi2_functions.c) both compile rattle_fmi2_common.c (and rattle_fmi_common.c, what every
 * FMI layer shares, of no FMI version).
 */
#ifndef RATTLE_FMI2_COMMON_H
#define RATTLE_FMI2_COMMON_H

#include <stddef.h>

#include "fmi2Functions.h"
#include "rattle_fmi_common.h"

/* rattle_state_check and rattle_state_room in FMI 2.0's words. */
RATTLE_INTERNAL int rattle_state_is_ours(const void* state, const char* guid, char* why,
                                         size_t why_size);
RATTLE_INTERNAL int rattle_state_fits(size_t size, size_t n, char* why, size_t why_size);

/* fmi2Instantiate's argument checks that both FMI 2.0 layers make: instanceName (non-blank,
 * UTF-8), fmuType (co-simulation only) and fmuGUID (equal to `guid`, unless that is "").  1,
 * or 0 with the refusal in why; `name` gets a printable copy of instanceName either way. */
RATTLE_INTERNAL int rattle_check_instantiate(const char* instanceName, int fmuType,
                                             const char* fmuGUID, const char* guid, char* name,
                                             size_t name_size, char* why, size_t why_size);

/* A refusal of fmi2Instantiate to the host's logger, before any instance exists:
 * "<prefix>fmi2Instantiate: <message>", passed verbatim (never as a format string). */
RATTLE_INTERNAL void rattle_instantiate_log(const fmi2CallbackFunctions* functions,
                                            const char* name, fmi2Status status,
                                            const char* prefix, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* The refusals of what these FMUs do not provide (the modelDescription says so). */
#define RATTLE_NO_DIRECTIONAL_DERIVATIVES                                                      \
    "not provided by this FMU (providesDirectionalDerivative = false)"
#define RATTLE_NO_INPUT_DERIVATIVES                                                            \
    "not provided by this FMU (canInterpolateInputs = false): set pinion.a as an input "      \
    "instead; nothing stored"
#define RATTLE_NO_OUTPUT_DERIVATIVES "not provided by this FMU (maxOutputDerivativeOrder = 0)"
#define RATTLE_NO_ASYNCHRONOUS_STEP                                                            \
    "no asynchronous step to cancel: every fmi2DoStep of this FMU completes within the call "  \
    "(canRunAsynchronuously = false)"
/* The refusal of a status inquiry that FMI 2.0 does not define for the function called, or
 * that only means something after fmi2Pending (never returned): `allowed` names what is. */
RATTLE_INTERNAL void rattle_status_refusal(char* why, size_t why_size, int kind,
                                           const char* allowed);

#endif
