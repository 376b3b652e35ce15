/* uavcas NFQUEUE delay helper: the compiled verdict loop of uavcas.emulation.nfqdelay.
 *
 * Same job and control protocol as the pure-Python daemon (see nfqdelay.py): hold every packet
 * of queue N for the delay of its physical out port, then accept it. What makes it hold under
 * floods on two shared cores:
 *   - the due time is the packet's *kernel* receive timestamp (NFQA_TIMESTAMP, the same stamp
 *     the switch captures carry) plus the delay, so time spent in the softirq backlog and in the
 *     socket before this process runs is not added to the delay;
 *   - recvmmsg drains up to 64 packets per call, and due packets are released between batches,
 *     so a burst never holds back a release;
 *   - verdicts due together go out in one sendmsg; a timerfd armed at absolute deadlines with
 *     1 ns timer slack wakes it; SCHED_FIFO (when allowed) so CPU-bound work cannot delay it.
 *
 * Pacing (a port given a rate): the port's frames are also served FIFO by a token bucket of that
 * rate and a depth of `burst` bytes, in virtual time, exactly the link model the fidelity audit
 * checks (uavcas.fidelity.fifo):
 *     ready_k = stamp_k + delay
 *     start_k = max(ready_k, start_{k-1}, Z_{k-1})
 *     Z_k     = max(Z_{k-1}, start_k - 8 burst / rate) + 8 len_k / rate
 * and each frame is released at start_k; a frame that finds `limit` frames ready and not started
 * at ready_k is dropped (the queue tail). Why here and not in HTB alone: a backlogged HTB class
 * whose host froze for 5-48 ms refills only its one-frame bucket during the freeze, so every
 * frame of the rest of its busy period leaves late by the freeze; here the schedule is computed
 * from the frames' stamps, so after a freeze the frames due during it go out at once and the
 * rest keep their times (the HTB class behind it is given a deep bucket, so it lets that
 * catch-up pass and only bounds the rate if this process is gone). A rate change re-times the
 * frames not yet started at the new rate (HTB charges a queued frame at dequeue), keeping Z.
 *
 * Build: cc -O2 -o uavcas-nfqdelay nfqdelay.c   (uavcas.emulation.nfqdelay builds it on demand)
 * Run:   uavcas-nfqdelay --queue N --ctl PATH [--rt PRIO] [--nice N] [--lead-us U] [--maxlen N]
 * Control (UNIX stream socket, one request line per connection, one JSON line back):
 *   "set NAME=US[,RATE_BPS,BURST_B,LIMIT_PKTS] ...", "get", "stop".
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <endian.h>
#include <errno.h>
#include <linux/netlink.h>
#include <net/if.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/timerfd.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#define NETLINK_NETFILTER_ 12
#define NFNL_SUBSYS_QUEUE 3
#define NFQNL_MSG_PACKET 0
#define NFQNL_MSG_VERDICT 1
#define NFQNL_MSG_CONFIG 2
#define NFQA_PACKET_HDR 1
#define NFQA_VERDICT_HDR 2
#define NFQA_TIMESTAMP 4
#define NFQA_IFINDEX_PHYSOUTDEV 8
#define NFQA_PAYLOAD_ 10
#define NFQA_CAP_LEN 16
#define NFQA_CFG_CMD 1
#define NFQA_CFG_PARAMS 2
#define NFQA_CFG_QUEUE_MAXLEN 3
#define NFQA_CFG_MASK 4
#define NFQA_CFG_FLAGS 5
#define NFQNL_CFG_CMD_BIND 1
#define NFQNL_COPY_PACKET 2
#define COPY_RANGE 4  /* the IPv4 header's first word: the kernel then also sends NFQA_CAP_LEN, the packet's length */
#define NFQA_CFG_F_FAIL_OPEN 1
#define NF_DROP 0
#define NF_ACCEPT 1
#define ETH_HLEN_ 14  /* NFQUEUE's length is the IP packet's; the captures and the model count the frame */
#define BATCH 64
#define VERDICT_LEN 32
#define N_BUCKETS 10
#define MAX_STALLS 32
#define STALL_NS 1000000  /* a release this late (1 ms) starts or extends a stall episode */

static const long BUCKET_US[N_BUCKETS] = {25, 50, 100, 200, 500, 1000, 2000, 5000, 10000, 1000000000L};

typedef struct { uint64_t due; uint32_t id; uint32_t port; uint64_t seq; } item_t;  /* port 0: not paced */

/* a paced port's frames not yet started, oldest first: ring[(head + i) % cap], seq = base + i */
typedef struct { int64_t ready, start, z_after; uint32_t len; } entry_t;
typedef struct {
    int64_t rate_bps, burst_b; uint32_t limit;
    int64_t z, last_start;  /* Z and start of the last frame admitted */
    int64_t z0, start0;      /* the same just before the ring's first frame (its released predecessor's) */
    entry_t *ring; size_t head, n, cap; uint64_t base;
    uint64_t paced, drops;
    int retimed;  /* re-timed by the request being handled: its heap items need their new starts */
} port_t;

static struct {
    int nl, tfd, ctl, ts_sock;
    uint16_t queue;
    int64_t lead_ns;
    item_t *heap; size_t n, cap;
    int64_t *delay_ns; char **names; port_t *ports; size_t n_if;  /* by ifindex */
    char *out; size_t out_len, out_cap;
    uint64_t packets, overflows, unknown_port, kernel_ts, no_len, max_lag_ns;
    uint64_t lag_hist[N_BUCKETS], recv_hist[N_BUCKETS], wake_hist[N_BUCKETS];
    int64_t armed_at, max_loop_ns, max_loop_at;  /* timer target; slowest loop iteration and when */
    struct { int64_t t_real, max_lag; uint64_t n; } stalls[MAX_STALLS]; int n_stalls, in_stall;
    volatile sig_atomic_t stop;
    const char *ctl_path;
} S;

static int64_t now_ns(clockid_t c) {
    struct timespec ts;
    clock_gettime(c, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void die(const char *what) {
    fprintf(stderr, "uavcas-nfqdelay: %s: %s\n", what, strerror(errno));
    exit(1);
}

static void *xrealloc(void *p, size_t n) {
    void *q = realloc(p, n);
    if (!q) die("out of memory");
    return q;
}

static void bucket(uint64_t *hist, int64_t ns) {
    long us = ns < 0 ? 0 : (long)(ns / 1000);
    for (int k = 0; k < N_BUCKETS; k++)
        if (us <= BUCKET_US[k]) { hist[k]++; return; }
}

/* heap ------------------------------------------------------------------------------------ */
static void heap_push(uint64_t due, uint32_t id, uint32_t port, uint64_t seq) {
    if (S.n == S.cap) { S.cap = S.cap ? 2 * S.cap : 4096; S.heap = xrealloc(S.heap, S.cap * sizeof(item_t)); }
    size_t i = S.n++;
    while (i > 0) {
        size_t p = (i - 1) / 2;
        if (S.heap[p].due <= due) break;
        S.heap[i] = S.heap[p];
        i = p;
    }
    S.heap[i].due = due; S.heap[i].id = id; S.heap[i].port = port; S.heap[i].seq = seq;
}

static void sift_down(size_t i) {
    item_t it = S.heap[i];
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= S.n) break;
        if (c + 1 < S.n && S.heap[c + 1].due < S.heap[c].due) c++;
        if (it.due <= S.heap[c].due) break;
        S.heap[i] = S.heap[c];
        i = c;
    }
    S.heap[i] = it;
}

static item_t heap_pop(void) {
    item_t top = S.heap[0];
    if (--S.n) { S.heap[0] = S.heap[S.n]; sift_down(0); }
    return top;
}

/* netlink ---------------------------------------------------------------------------------- */
static size_t put_attr(char *buf, size_t off, uint16_t type, const void *data, uint16_t len) {
    struct nlattr *a = (struct nlattr *)(buf + off);
    a->nla_len = 4 + len; a->nla_type = type;
    memcpy(buf + off + 4, data, len);
    size_t total = (4 + len + 3) & ~3u;
    memset(buf + off + 4 + len, 0, total - 4 - len);
    return off + total;
}

static size_t put_hdr(char *buf, uint16_t msg, uint16_t flags) {
    struct nlmsghdr *h = (struct nlmsghdr *)buf;
    h->nlmsg_type = (NFNL_SUBSYS_QUEUE << 8) | msg; h->nlmsg_flags = flags; h->nlmsg_seq = 0; h->nlmsg_pid = 0;
    buf[16] = AF_UNSPEC; buf[17] = 0;
    uint16_t q = htons(S.queue);
    memcpy(buf + 18, &q, 2);
    return 20;
}

static void config(const char *attrs_desc, char *buf, size_t len) {
    ((struct nlmsghdr *)buf)->nlmsg_len = len;
    if (send(S.nl, buf, len, 0) < 0) die(attrs_desc);
    char reply[4096];
    ssize_t r = recv(S.nl, reply, sizeof reply, 0);
    if (r < 0) die(attrs_desc);
    struct nlmsghdr *h = (struct nlmsghdr *)reply;
    if (h->nlmsg_type == NLMSG_ERROR) {
        int code = *(int *)(reply + 16);
        if (code != 0) { errno = -code; die(attrs_desc); }
    }
}

static void bind_queue(uint32_t maxlen) {
    char buf[256];
    size_t off = put_hdr(buf, NFQNL_MSG_CONFIG, NLM_F_REQUEST | NLM_F_ACK);
    struct { uint8_t cmd, pad; uint16_t pf; } __attribute__((packed)) cmd = {NFQNL_CFG_CMD_BIND, 0, htons(AF_INET)};
    off = put_attr(buf, off, NFQA_CFG_CMD, &cmd, sizeof cmd);
    config("nfqueue bind", buf, off);
    off = put_hdr(buf, NFQNL_MSG_CONFIG, NLM_F_REQUEST | NLM_F_ACK);
    struct { uint32_t range; uint8_t mode; } __attribute__((packed)) params = {htonl(COPY_RANGE), NFQNL_COPY_PACKET};
    off = put_attr(buf, off, NFQA_CFG_PARAMS, &params, sizeof params);
    uint32_t v = htonl(maxlen);
    off = put_attr(buf, off, NFQA_CFG_QUEUE_MAXLEN, &v, 4);
    v = htonl(NFQA_CFG_F_FAIL_OPEN);
    off = put_attr(buf, off, NFQA_CFG_MASK, &v, 4);
    off = put_attr(buf, off, NFQA_CFG_FLAGS, &v, 4);
    config("nfqueue params", buf, off);
}

static void add_verdict_v(uint32_t id, uint32_t verdict) {
    if (S.out_len + VERDICT_LEN > S.out_cap) { S.out_cap = S.out_cap ? 2 * S.out_cap : 65536; S.out = xrealloc(S.out, S.out_cap); }
    char *b = S.out + S.out_len;
    size_t off = put_hdr(b, NFQNL_MSG_VERDICT, NLM_F_REQUEST);
    uint32_t vh[2] = {htonl(verdict), htonl(id)};
    off = put_attr(b, off, NFQA_VERDICT_HDR, vh, 8);
    ((struct nlmsghdr *)b)->nlmsg_len = off;
    S.out_len += VERDICT_LEN;
}

static void add_verdict(uint32_t id) { add_verdict_v(id, NF_ACCEPT); }

/* pacing ----------------------------------------------------------------------------------- */
static entry_t *ring_at(port_t *p, size_t i) { return &p->ring[(p->head + i) % p->cap]; }

static void ring_push(port_t *p, entry_t e) {
    if (p->n == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 256;
        entry_t *r = xrealloc(NULL, cap * sizeof *r);
        for (size_t i = 0; i < p->n; i++) r[i] = *ring_at(p, i);
        free(p->ring); p->ring = r; p->head = 0; p->cap = cap;
    }
    p->ring[(p->head + p->n) % p->cap] = e; p->n++;
}

/* forget the frames released by `now` (they can no longer be re-timed or be queued ahead) */
static void ring_prune(port_t *p, int64_t now) {
    while (p->n && ring_at(p, 0)->start - S.lead_ns <= now) {
        p->start0 = ring_at(p, 0)->start; p->z0 = ring_at(p, 0)->z_after;
        p->head = (p->head + 1) % p->cap; p->n--; p->base++;
    }
}

/* frames of the ring not started at t: starts are non-decreasing along the ring */
static size_t backlog_at(port_t *p, int64_t t) {
    size_t lo = 0, hi = p->n;
    while (lo < hi) { size_t mid = (lo + hi) / 2; if (ring_at(p, mid)->start > t) hi = mid; else lo = mid + 1; }
    return p->n - lo;
}

/* the model's token bucket: start and Z after a frame of `len` bytes ready at `ready` */
static void charge(const port_t *p, int64_t ready, uint32_t len, int64_t prev_start, int64_t z, int64_t *start, int64_t *z_after) {
    int64_t st = ready;
    if (prev_start > st) st = prev_start;
    if (z > st) st = z;
    int64_t credit = st - (int64_t)((double)p->burst_b * 8e9 / (double)p->rate_bps);
    if (credit > z) z = credit;
    *start = st; *z_after = z + (int64_t)((double)len * 8e9 / (double)p->rate_bps);
}

static void pace(uint32_t ifindex, uint32_t id, int64_t ready, uint32_t len, int64_t now) {
    port_t *p = &S.ports[ifindex];
    ring_prune(p, now);
    if (p->limit && backlog_at(p, ready) >= p->limit) { p->drops++; add_verdict_v(id, NF_DROP); return; }
    entry_t e = {ready, 0, 0, len};
    charge(p, ready, len, p->last_start, p->z, &e.start, &e.z_after);
    p->z = e.z_after; p->last_start = e.start; p->paced++;
    ring_push(p, e);
    heap_push((uint64_t)e.start, id, ifindex, p->base + p->n - 1);
}

/* a new rate: re-time the frames not yet released, as HTB charges a queued frame at dequeue */
static void retime(uint32_t ifindex, int64_t now) {
    port_t *p = &S.ports[ifindex];
    ring_prune(p, now);
    if (!p->n) return;
    int64_t last_start = p->start0, zz = p->z0;
    for (size_t i = 0; i < p->n; i++) {
        entry_t *e = ring_at(p, i);
        charge(p, e->ready, e->len, last_start, zz, &e->start, &e->z_after);
        last_start = e->start; zz = e->z_after;
    }
    p->last_start = last_start; p->z = zz;
    p->retimed = 1;
}

/* the release heap after re-timing: each re-timed frame takes its new start (one pass, then heapify) */
static void rekey(void) {
    int any = 0;
    for (size_t k = 0; k < S.n; k++) {
        uint32_t i = S.heap[k].port;
        if (!i || i >= S.n_if || !S.ports[i].retimed) continue;
        port_t *p = &S.ports[i];
        if (S.heap[k].seq >= p->base && S.heap[k].seq < p->base + p->n)
            S.heap[k].due = (uint64_t)ring_at(p, S.heap[k].seq - p->base)->start;
        any = 1;
    }
    for (size_t i = 0; i < S.n_if; i++) S.ports[i].retimed = 0;
    if (any) for (size_t k = S.n / 2; k-- > 0;) sift_down(k);
}

static void flush(void) {
    size_t done = 0;
    while (done < S.out_len) {
        size_t chunk = S.out_len - done > 60000 ? 60000 : S.out_len - done;  /* whole messages: 60000 = 1875 x 32 */
        ssize_t r = send(S.nl, S.out + done, chunk, 0);
        if (r < 0) {
            if (errno == EINTR) continue;
            if (errno == EAGAIN || errno == ENOBUFS) { struct pollfd p = {S.nl, POLLOUT, 0}; poll(&p, 1, 10); continue; }
            die("verdict");
        }
        done += chunk;
    }
    S.out_len = 0;
}

static void release_due(void) {
    int64_t now = now_ns(CLOCK_MONOTONIC);
    while (S.n && (int64_t)S.heap[0].due <= now + S.lead_ns) {
        item_t it = heap_pop();
        add_verdict(it.id);
        int64_t lag = now - (int64_t)it.due;
        if (lag > 0 && (uint64_t)lag > S.max_lag_ns) S.max_lag_ns = lag;
        bucket(S.lag_hist, lag);
        if (lag > STALL_NS) {
            if (!S.in_stall && S.n_stalls < MAX_STALLS) {
                S.stalls[S.n_stalls].t_real = now_ns(CLOCK_REALTIME) - lag; S.stalls[S.n_stalls].max_lag = 0;
                S.stalls[S.n_stalls].n = 0; S.n_stalls++;
            }
            S.in_stall = 1;
            if (S.n_stalls && S.n_stalls <= MAX_STALLS) {
                if (lag > S.stalls[S.n_stalls - 1].max_lag) S.stalls[S.n_stalls - 1].max_lag = lag;
                S.stalls[S.n_stalls - 1].n++;
            }
        } else S.in_stall = 0;
    }
}

static void on_packet(const char *m, size_t len, int64_t recv_mono, int64_t real_minus_mono) {
    uint32_t id = 0, ifindex = 0, cap_len = 0, ip_len = 0; int have_id = 0; int64_t ts_mono = 0;
    size_t off = 20;
    while (off + 4 <= len) {
        const struct nlattr *a = (const struct nlattr *)(m + off);
        if (a->nla_len < 4) break;
        uint16_t type = a->nla_type & NLA_TYPE_MASK;
        const char *p = m + off + 4;
        if (type == NFQA_PACKET_HDR) { memcpy(&id, p, 4); id = ntohl(id); have_id = 1; }
        else if (type == NFQA_IFINDEX_PHYSOUTDEV) { memcpy(&ifindex, p, 4); ifindex = ntohl(ifindex); }
        else if (type == NFQA_CAP_LEN) { memcpy(&cap_len, p, 4); cap_len = ntohl(cap_len); }
        else if (type == NFQA_PAYLOAD_ && a->nla_len >= 8) { uint16_t tl; memcpy(&tl, p + 2, 2); ip_len = ntohs(tl); }
        else if (type == NFQA_TIMESTAMP) {
            uint64_t sec, usec;
            memcpy(&sec, p, 8); memcpy(&usec, p + 8, 8);
            sec = be64toh(sec); usec = be64toh(usec);
            ts_mono = (int64_t)sec * 1000000000LL + (int64_t)usec * 1000 - real_minus_mono;
        }
        off += (a->nla_len + 3) & ~3u;
    }
    if (!have_id) return;
    S.packets++;
    int64_t base = recv_mono;
    /* a stamp from the future or older than a second is not this packet's arrival */
    if (ts_mono && ts_mono <= recv_mono + 1000 && recv_mono - ts_mono < 1000000000LL) {
        base = ts_mono; S.kernel_ts++;
        bucket(S.recv_hist, recv_mono - ts_mono);
    }
    int64_t d = 0;
    if (ifindex < S.n_if && S.names[ifindex]) d = S.delay_ns[ifindex];
    else S.unknown_port++;
    if (ifindex < S.n_if && S.ports[ifindex].rate_bps > 0) {
        if (!cap_len) cap_len = ip_len;  /* a packet no longer than the copy range */
        if (!cap_len) { S.no_len++; cap_len = 1500; }
        pace(ifindex, id, base + d, cap_len + ETH_HLEN_, recv_mono);
    } else if (d <= 0) add_verdict(id);
    else heap_push((uint64_t)(base + d), id, 0, 0);
}

static void on_netlink(void) {
    static char bufs[BATCH][512];
    struct mmsghdr msgs[BATCH]; struct iovec iov[BATCH];
    for (int rounds = 0; rounds < 64; rounds++) {
        for (int k = 0; k < BATCH; k++) {
            iov[k].iov_base = bufs[k]; iov[k].iov_len = sizeof bufs[k];
            memset(&msgs[k].msg_hdr, 0, sizeof msgs[k].msg_hdr);
            msgs[k].msg_hdr.msg_iov = &iov[k]; msgs[k].msg_hdr.msg_iovlen = 1;
        }
        int got = recvmmsg(S.nl, msgs, BATCH, MSG_DONTWAIT, NULL);
        if (got < 0) {
            if (errno == EAGAIN || errno == EINTR) return;
            if (errno == ENOBUFS) { S.overflows++; continue; }  /* the kernel failed open */
            die("recv");
        }
        int64_t mono = now_ns(CLOCK_MONOTONIC), real = now_ns(CLOCK_REALTIME);
        for (int k = 0; k < got; k++) {
            const char *m = bufs[k]; size_t left = msgs[k].msg_len;
            while (left >= 16) {
                const struct nlmsghdr *h = (const struct nlmsghdr *)m;
                if (h->nlmsg_len < 16 || h->nlmsg_len > left) break;
                if (h->nlmsg_type == ((NFNL_SUBSYS_QUEUE << 8) | NFQNL_MSG_PACKET))
                    on_packet(m, h->nlmsg_len, mono, real - mono);
                size_t step = NLMSG_ALIGN(h->nlmsg_len);
                if (step >= left) break;
                m += step; left -= step;
            }
        }
        release_due();  /* between batches: a burst never holds a due packet back */
        flush();
        if (got < BATCH) return;
    }
}

/* control ---------------------------------------------------------------------------------- */
typedef struct { char *s; size_t n, cap; } sbuf;

static void sb_add(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_add(sbuf *b, const char *fmt, ...) {
    for (;;) {
        va_list ap; va_start(ap, fmt);
        int w = vsnprintf(b->s + b->n, b->cap - b->n, fmt, ap);
        va_end(ap);
        if (w >= 0 && (size_t)w < b->cap - b->n) { b->n += w; return; }
        b->cap = b->cap * 2 + (w > 0 ? (size_t)w : 0) + 256;
        b->s = xrealloc(b->s, b->cap);
    }
}

static void sb_table(sbuf *b) {
    sb_add(b, "\"table\": {");
    int first = 1;
    for (size_t k = 0; k < S.n_if; k++)
        if (S.names[k]) { sb_add(b, "%s\"%s\": %lld", first ? "" : ", ", S.names[k], (long long)(S.delay_ns[k] / 1000)); first = 0; }
    sb_add(b, "}");
}

/* "pacing": {NAME: [rate_bps, burst_b, limit_pkts, frames paced, tail drops]} for the paced ports */
static void sb_pacing(sbuf *b) {
    sb_add(b, "\"pacing\": {");
    int first = 1;
    for (size_t k = 0; k < S.n_if; k++) {
        port_t *p = &S.ports[k];
        if (!S.names[k] || (!p->rate_bps && !p->paced)) continue;
        sb_add(b, "%s\"%s\": [%lld, %lld, %u, %llu, %llu]", first ? "" : ", ", S.names[k], (long long)p->rate_bps,
               (long long)p->burst_b, p->limit, (unsigned long long)p->paced, (unsigned long long)p->drops);
        first = 0;
    }
    sb_add(b, "}");
}

static void sb_hist(sbuf *b, const char *key, const uint64_t *hist) {
    sb_add(b, "\"%s\": {", key);
    for (int k = 0; k < N_BUCKETS; k++) sb_add(b, "%s\"%ld\": %llu", k ? ", " : "", BUCKET_US[k], (unsigned long long)hist[k]);
    sb_add(b, "}");
}

/* one item of "set": NAME=US or NAME=US,RATE_BPS,BURST_B,LIMIT_PKTS (rate 0: delay only) */
static int set_port(const char *name, const char *value, sbuf *err) {
    long long us = 0, rate = 0, burst = 0, limit = 0;
    char tail = 0;
    int got = sscanf(value, "%lld,%lld,%lld,%lld%c", &us, &rate, &burst, &limit, &tail);
    if (!(got == 1 || got == 4) || us < 0 || rate < 0 || burst < 0 || limit < 0 || (rate > 0 && burst <= 0)) {
        sb_add(err, "bad item %s=%s", name, value); return -1;
    }
    unsigned idx = if_nametoindex(name);
    if (!idx) { sb_add(err, "no interface %s", name); return -1; }
    if (idx >= S.n_if) {
        size_t n = idx + 64;
        S.delay_ns = xrealloc(S.delay_ns, n * sizeof *S.delay_ns); S.names = xrealloc(S.names, n * sizeof *S.names);
        S.ports = xrealloc(S.ports, n * sizeof *S.ports);
        for (size_t k = S.n_if; k < n; k++) { S.delay_ns[k] = 0; S.names[k] = NULL; memset(&S.ports[k], 0, sizeof S.ports[k]); }
        S.n_if = n;
    }
    if (!S.names[idx]) S.names[idx] = strdup(name);
    S.delay_ns[idx] = us * 1000;
    port_t *p = &S.ports[idx];
    int retimed = got == 4 && (p->rate_bps != rate || p->burst_b != burst);
    if (got == 4) { p->rate_bps = rate; p->burst_b = burst; p->limit = (uint32_t)limit; }
    if (retimed && rate > 0) retime(idx, now_ns(CLOCK_MONOTONIC));
    /* a port no longer paced: its queued frames keep their times, new ones are only delayed */
    return 0;
}

static void handle(char *line, sbuf *out) {
    char *save = NULL, *op = strtok_r(line, " \t\r\n", &save);
    if (op && !strcmp(op, "set")) {
        sbuf err = {0};
        for (char *tok; (tok = strtok_r(NULL, " \t\r\n", &save));) {
            char *eq = strchr(tok, '=');
            if (!eq) { sb_add(&err, "bad item %s", tok); break; }
            *eq = 0;
            if (set_port(tok, eq + 1, &err)) break;
        }
        rekey();
        if (err.n) { sb_add(out, "{\"ok\": false, \"error\": \"%s\"}", err.s); free(err.s); return; }
        sb_add(out, "{\"ok\": true, "); sb_table(out); sb_add(out, ", "); sb_pacing(out); sb_add(out, "}");
    } else if (op && !strcmp(op, "get")) {
        sb_add(out, "{\"ok\": true, "); sb_table(out); sb_add(out, ", "); sb_pacing(out);
        sb_add(out, ", \"stats\": {\"impl\": \"c\", \"packets\": %llu, \"queued\": %zu, \"overflows\": %llu, "
               "\"unknown_port\": %llu, \"kernel_ts\": %llu, \"no_len\": %llu, \"max_lag_us\": %.1f, \"lead_us\": %.1f, ",
               (unsigned long long)S.packets, S.n, (unsigned long long)S.overflows,
               (unsigned long long)S.unknown_port, (unsigned long long)S.kernel_ts, (unsigned long long)S.no_len,
               S.max_lag_ns / 1000.0,
               S.lead_ns / 1000.0);
        sb_hist(out, "lag_hist_us", S.lag_hist); sb_add(out, ", "); sb_hist(out, "recv_hist_us", S.recv_hist);
        sb_add(out, ", "); sb_hist(out, "wake_hist_us", S.wake_hist);
        sb_add(out, ", \"max_loop_us\": %.1f, \"max_loop_t_unix\": %.6f, \"stalls\": [", S.max_loop_ns / 1000.0,
               S.max_loop_at / 1e9);
        for (int k = 0; k < S.n_stalls; k++)
            sb_add(out, "%s{\"t_unix\": %.6f, \"max_lag_us\": %.1f, \"packets\": %llu}", k ? ", " : "",
                   S.stalls[k].t_real / 1e9, S.stalls[k].max_lag / 1000.0, (unsigned long long)S.stalls[k].n);
        sb_add(out, "]}}");
    } else if (op && !strcmp(op, "stop")) {
        S.stop = 1; sb_add(out, "{\"ok\": true}");
    } else {
        sb_add(out, "{\"ok\": false, \"error\": \"unknown op %s\"}", op ? op : "");
    }
}

static void on_ctl(void) {
    int c = accept4(S.ctl, NULL, NULL, SOCK_CLOEXEC);
    if (c < 0) return;
    struct timeval tv = {0, 200000};  /* a stuck client must not hold the verdict loop long */
    setsockopt(c, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    setsockopt(c, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sbuf in = {0};
    char chunk[4096];
    for (;;) {
        ssize_t r = recv(c, chunk, sizeof chunk, 0);
        if (r <= 0) break;
        sb_add(&in, "%.*s", (int)r, chunk);
        if (memchr(chunk, '\n', r)) break;
    }
    sbuf out = {0};
    handle(in.s ? in.s : (char *)"", &out);
    sb_add(&out, "\n");
    for (size_t done = 0; done < out.n;) {
        ssize_t w = send(c, out.s + done, out.n - done, MSG_NOSIGNAL);
        if (w <= 0) break;
        done += w;
    }
    free(in.s); free(out.s);
    close(c);
}

/* main ------------------------------------------------------------------------------------- */
static void arm(void) {
    struct itimerspec its = {0};
    if (S.n) {
        int64_t due = (int64_t)S.heap[0].due - S.lead_ns;
        if (due <= 0) due = 1;
        its.it_value.tv_sec = due / 1000000000LL; its.it_value.tv_nsec = due % 1000000000LL;
        S.armed_at = due;
    } else S.armed_at = 0;
    timerfd_settime(S.tfd, TFD_TIMER_ABSTIME, &its, NULL);
}

static void on_signal(int sig) { (void)sig; S.stop = 1; }

int main(int argc, char **argv) {
    int queue = 0, rt = 0, nice_v = -15; long lead_us = 0; unsigned maxlen = 65536;  /* paced ports hold their queues here now (up to 2000 frames each) */
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--queue") && k + 1 < argc) queue = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--ctl") && k + 1 < argc) S.ctl_path = argv[++k];
        else if (!strcmp(argv[k], "--rt") && k + 1 < argc) rt = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--nice") && k + 1 < argc) nice_v = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--lead-us") && k + 1 < argc) lead_us = atol(argv[++k]);
        else if (!strcmp(argv[k], "--maxlen") && k + 1 < argc) maxlen = (unsigned)atol(argv[++k]);
        else { fprintf(stderr, "usage: %s --queue N --ctl PATH [--rt PRIO] [--nice N] [--lead-us U] [--maxlen N]\n", argv[0]); return 2; }
    }
    if (!S.ctl_path) { fprintf(stderr, "uavcas-nfqdelay: --ctl is required\n"); return 2; }
    S.queue = (uint16_t)queue; S.lead_ns = lead_us * 1000;
    prctl(PR_SET_TIMERSLACK, 1, 0, 0, 0);
    setpriority(PRIO_PROCESS, 0, nice_v);
    if (rt > 0) {
        struct sched_param sp = {.sched_priority = rt};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) < 0) fprintf(stderr, "uavcas-nfqdelay: SCHED_FIFO refused (%s); using nice %d\n", strerror(errno), nice_v);
    }
    mlockall(MCL_CURRENT | MCL_FUTURE);  /* no page fault in the verdict path (best effort) */
    /* Receive timestamps for every packet: one socket asking for them turns them on kernel-wide. */
    S.ts_sock = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    int one = 1;
    if (S.ts_sock >= 0) setsockopt(S.ts_sock, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);

    S.nl = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_NETFILTER_);
    if (S.nl < 0) die("netlink socket");
    int rcv = 8 << 20;
    if (setsockopt(S.nl, SOL_SOCKET, SO_RCVBUFFORCE, &rcv, sizeof rcv) < 0) setsockopt(S.nl, SOL_SOCKET, SO_RCVBUF, &rcv, sizeof rcv);
    int snd = 4 << 20;
    if (setsockopt(S.nl, SOL_SOCKET, SO_SNDBUFFORCE, &snd, sizeof snd) < 0) setsockopt(S.nl, SOL_SOCKET, SO_SNDBUF, &snd, sizeof snd);
    struct sockaddr_nl sa = {.nl_family = AF_NETLINK};
    if (bind(S.nl, (struct sockaddr *)&sa, sizeof sa) < 0) die("netlink bind");
    bind_queue(maxlen);

    S.tfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (S.tfd < 0) die("timerfd");
    unlink(S.ctl_path);
    S.ctl = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    struct sockaddr_un su = {.sun_family = AF_UNIX};
    strncpy(su.sun_path, S.ctl_path, sizeof su.sun_path - 1);
    if (bind(S.ctl, (struct sockaddr *)&su, sizeof su) < 0 || listen(S.ctl, 16) < 0) die("control socket");

    struct sigaction act = {.sa_handler = on_signal};
    sigaction(SIGTERM, &act, NULL); sigaction(SIGINT, &act, NULL);
    signal(SIGPIPE, SIG_IGN);
    int ep = epoll_create1(EPOLL_CLOEXEC);
    struct epoll_event ev = {.events = EPOLLIN};
    ev.data.fd = S.nl; epoll_ctl(ep, EPOLL_CTL_ADD, S.nl, &ev);
    ev.data.fd = S.tfd; epoll_ctl(ep, EPOLL_CTL_ADD, S.tfd, &ev);
    ev.data.fd = S.ctl; epoll_ctl(ep, EPOLL_CTL_ADD, S.ctl, &ev);
    printf("ready\n");
    fflush(stdout);
    while (!S.stop) {
        struct epoll_event evs[4];
        int n = epoll_wait(ep, evs, 4, 1000);
        int64_t woke = now_ns(CLOCK_MONOTONIC);
        for (int k = 0; k < n; k++) {
            int fd = evs[k].data.fd;
            if (fd == S.nl) on_netlink();
            else if (fd == S.tfd) {
                uint64_t x;
                if (read(S.tfd, &x, 8) == 8 && S.armed_at) bucket(S.wake_hist, woke - S.armed_at);
            }
            else if (fd == S.ctl) on_ctl();
        }
        release_due();
        flush();
        arm();
        int64_t took = now_ns(CLOCK_MONOTONIC) - woke;
        if (took > S.max_loop_ns) { S.max_loop_ns = took; S.max_loop_at = now_ns(CLOCK_REALTIME); }
    }
    unlink(S.ctl_path);
    return 0;
}
