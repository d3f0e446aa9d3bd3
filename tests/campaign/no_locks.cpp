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

int forward(const char* name, int fd, int cmd, void* arg) {
    static FcntlFn real_fcntl = reinterpret_cast<FcntlFn>(dlsym(RTLD_NEXT, "fcntl"));
    static FcntlFn real_fcntl64 = reinterpret_cast<FcntlFn>(dlsym(RTLD_NEXT, "fcntl64"));
    FcntlFn f = name[5] == '6' && real_fcntl64 ? real_fcntl64 : real_fcntl;
    return f(fd, cmd, arg);
}

}  // namespace

extern "C" {

int flock(int, int) {
    const char* e = std::getenv("HOPPER_NO_LOCKS_FLOCK");
    errno = e && std::strcmp(e, "ENOSYS") == 0 ? ENOSYS : ENOLCK;
    return -1;
}

int fcntl(int fd, int cmd, ...) {
    va_list ap;
    va_start(ap, cmd);
    void* arg = va_arg(ap, void*);
    va_end(ap);
    if (is_lock_command(cmd)) {
        errno = ENOLCK;
        return -1;
    }
    return forward("fcntl", fd, cmd, arg);
}

int fcntl64(int fd, int cmd, ...) {
    va_list ap;
    va_start(ap, cmd);
    void* arg = va_arg(ap, void*);
    va_end(ap);
    if (is_lock_command(cmd)) {
        errno = ENOLCK;
        return -1;
    }
    return forward("fcntl64", fd, cmd, arg);
}

}  // extern "C"
