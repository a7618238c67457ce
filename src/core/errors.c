/* errors.c - how a library call reports: the first error kept in a caller's cb_error (core.h). */
#include "crowdbake/core.h"

#include <stdarg.h>
#include <stdio.h>

static void fail_v(cb_error *err, cb_status status, cb_setting setting, const char *fmt, va_list ap)
{
    if (err && err->status == CB_OK) {
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        err->status = status;
        err->setting = setting;
    }
}

cb_status cb_fail(cb_error *err, cb_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_v(err, status, CB_SETTING_NONE, fmt, ap);
    va_end(ap);
    return status;
}

cb_status cb_fail_setting(cb_error *err, cb_status status, cb_setting setting, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_v(err, status, setting, fmt, ap);
    va_end(ap);
    return status;
}
