// A sampling profiler preloaded into a render (bench/profile_threads.py): every thread gets a
// timer on its own CPU time (timer_create(CLOCK_THREAD_CPUTIME_ID), one SIGPROF per period of
// the thread's CPU), whose handler records the thread and its stack. For machines where perf
// has no events or is not installed. Built by profile_threads.py:
//   cc -O2 -shared -fPIC cpu_sampler.c -o libcpu_sampler.so -ldl -lrt
// From Python: ctypes.CDLL(None).cpu_sampler_start(b"out.bin", 1000); ...; cpu_sampler_stop()
// writes the samples (u64 count, then records of u32 tid, u32 depth, u64 pc[Depth]) to out.bin
// and the process's memory map to out.bin.maps.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <time.h>
#include <ucontext.h>
#include <unistd.h>

enum { Depth = 14, MaxThreads = 1024 };
typedef struct {
    uint32_t tid, depth;
    uint64_t pc[Depth];
} Sample;

static Sample *samples;
static const size_t capacity = 1 << 20;
static size_t count;
static char out_path[512];
static timer_t timers[MaxThreads];
static int n_timers, armed_us;

// The interrupted pc, then the callers (backtrace's first two frames are the handler and the
// signal trampoline, its third the interrupted function again).
static void on_sigprof(int sig, siginfo_t *info, void *context) {
    (void)sig, (void)info;
    const int saved_errno = errno;
    const size_t i = __atomic_fetch_add(&count, 1, __ATOMIC_RELAXED);
    if (i < capacity) {
        Sample *s = &samples[i];
        s->tid = (uint32_t)syscall(SYS_gettid);
        s->pc[0] = (uint64_t)((ucontext_t *)context)->uc_mcontext.gregs[REG_RIP];
        void *frames[Depth + 2];
        const int n = backtrace(frames, Depth + 2);
        uint32_t k = 1;
        for (int j = 3; j < n && k < Depth; ++j) s->pc[k++] = (uint64_t)frames[j];
        s->depth = k;
    }
    errno = saved_errno;
}

static void arm(timer_t t, int us) {
    const struct itimerspec spec = {{0, us * 1000L}, {0, us * 1000L}};
    timer_settime(t, 0, &spec, NULL);
}

// A disarmed timer on the calling thread's CPU time, armed while sampling.
static void add_thread_timer(void) {
    struct sigevent ev;
    memset(&ev, 0, sizeof ev);
    ev.sigev_notify = SIGEV_THREAD_ID, ev.sigev_signo = SIGPROF;
    ev._sigev_un._tid = (pid_t)syscall(SYS_gettid);
    timer_t t;
    if (timer_create(CLOCK_THREAD_CPUTIME_ID, &ev, &t) != 0) return;
    const int i = __atomic_fetch_add(&n_timers, 1, __ATOMIC_SEQ_CST);
    if (i >= MaxThreads) return;
    timers[i] = t;
    const int us = __atomic_load_n(&armed_us, __ATOMIC_SEQ_CST);
    if (us) arm(t, us);
}

typedef struct {
    void *(*start)(void *);
    void *arg;
} ThreadStart;

static void *thread_start(void *p) {
    const ThreadStart s = *(ThreadStart *)p;
    free(p);
    add_thread_timer();
    return s.start(s.arg);
}

// Every thread the process makes (the thread pool's workers) starts with its timer.
int pthread_create(pthread_t *thread, const pthread_attr_t *attr, void *(*start)(void *), void *arg) {
    static int (*next)(pthread_t *, const pthread_attr_t *, void *(*)(void *), void *);
    if (!next) next = dlsym(RTLD_NEXT, "pthread_create");
    ThreadStart *s = malloc(sizeof *s);
    s->start = start, s->arg = arg;
    return next(thread, attr, thread_start, s);
}

__attribute__((constructor)) static void on_load(void) { add_thread_timer(); }

void cpu_sampler_start(const char *path, int period_us) {
    snprintf(out_path, sizeof out_path, "%s", path);
    if (!samples)
        samples = mmap(NULL, capacity * sizeof(Sample), PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    void *warm[4];
    backtrace(warm, 4); // loads the unwinder now, not in the handler
    count = 0;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_sigprof, sa.sa_flags = SA_SIGINFO | SA_RESTART;
    sigaction(SIGPROF, &sa, NULL);
    __atomic_store_n(&armed_us, period_us, __ATOMIC_SEQ_CST);
    for (int i = 0; i < n_timers && i < MaxThreads; ++i) arm(timers[i], period_us);
}

void cpu_sampler_stop(void) {
    __atomic_store_n(&armed_us, 0, __ATOMIC_SEQ_CST);
    for (int i = 0; i < n_timers && i < MaxThreads; ++i) arm(timers[i], 0);
    const size_t n = count < capacity ? count : capacity;
    FILE *f = fopen(out_path, "wb");
    if (!f) return;
    fwrite(&n, sizeof n, 1, f);
    fwrite(samples, sizeof(Sample), n, f);
    fclose(f);
    char maps_path[600];
    snprintf(maps_path, sizeof maps_path, "%s.maps", out_path);
    FILE *in = fopen("/proc/self/maps", "r"), *out = fopen(maps_path, "w");
    char line[1024];
    while (in && out && fgets(line, sizeof line, in)) fputs(line, out);
    if (in) fclose(in);
    if (out) fclose(out);
}
