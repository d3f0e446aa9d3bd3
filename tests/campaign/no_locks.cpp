// LD_PRELOAD shim for the tests: a file system without locks (NFS without a lock daemon, Lustre
// mounted without flock). Every fcntl() lock command fails with ENOLCK and flock() with ENOLCK
// (NFS) or, with HOPPER_NO_LOCKS_FLOCK=ENOSYS in the environment, ENOSYS (Lustre); everything
// else goes to the C library.
#include <dlfcn.h>
#include <fcntl.h>
#include <sys/file.h>

#include <cerrno>
#include <cstdarg>
#include <cstdlib>
#include <cstring>

namespace {

bool is_lock_command(int cmd) {
    return cmd == F_SETLK || cmd == F_SETLKW || cmd == F_GETLK || cmd == F_OFD_SETLK ||
           cmd == F_OFD_SETLKW || cmd == F_OFD_GETLK;
}

using FcntlFn = int (*)(int, int, ...);

// The C library's fcntl64 (on 64-bit Linux the same call as fcntl), or fcntl without it.
FcntlFn real_fcntl() {
    static const FcntlFn f = [] {
        void* f64 = dlsym(RTLD_NEXT, "fcntl64");
        return reinterpret_cast<FcntlFn>(f64 ? f64 : dlsym(RTLD_NEXT, "fcntl"));
    }();
    return f;
}

}  // namespace

extern "C" {

int flock(int, int) {
    const char* e = std::getenv("HOPPER_NO_LOCKS_FLOCK");
    errno = e && std::strcmp(e, "ENOSYS") == 0 ? ENOSYS : ENOLCK;
    return -1;
}

// A lock command fails as on a file system without locks; anything else goes to the C library.
int fcntl(int fd, int cmd, ...) {
    va_list ap;
    va_start(ap, cmd);
    void* arg = va_arg(ap, void*);
    va_end(ap);
    if (is_lock_command(cmd)) {
        errno = ENOLCK;
        return -1;
    }
    return real_fcntl()(fd, cmd, arg);
}

// Callers built with large-file support call fcntl64: the same function.
int fcntl64(int fd, int cmd, ...) __attribute__((alias("fcntl")));

}  // extern "C"
