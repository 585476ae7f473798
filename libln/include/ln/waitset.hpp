// waitset.hpp — C++17 RAII wrapper of libln's waitset (docs/waiting.md): one thread waits for
// whatever comes first of samples, deadlines and publishers of inports, service requests,
// parameter overrides, file descriptors and timers, and runs the callback attached to each.
// Attach calls return an ln::waitset::attachment that detaches when destroyed; dispatching an
// event allocates nothing.  Failures throw ln::error.
#ifndef LN_WAITSET_HPP
#define LN_WAITSET_HPP

#include <ln/ln.hpp>
#include <ln/parameters.hpp>

#include <time.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>

namespace ln {

namespace detail {

// One attachment's callback.  libln hands its address back as each event's user_data, so
// dispatch is one virtual call on an object made when attaching.
struct wait_slot {
    virtual ~wait_slot() = default;
    virtual void fire(const ln_waitset_event& ev) = 0;
    std::uint32_t id = 0;
    bool dead = false;         // detached: events of it still in a batch are skipped
    wait_slot* prev = nullptr; // in the core's list of live slots (next: also of dead ones)
    wait_slot* next = nullptr;
};

template <typename F>
struct wait_slot_of final : wait_slot {
    explicit wait_slot_of(F f) : fn(std::move(f)) {}
    void fire(const ln_waitset_event& ev) override { fn(ev); }
    F fn;
};

// Calls fn(args...) if it takes them, else fn(): callbacks may ignore what an event says.
template <typename F, typename... A>
void call_with(F& fn, A&&... args)
{
    if constexpr (std::is_invocable_v<F&, A...>) {
        fn(std::forward<A>(args)...);
    } else {
        static_assert(std::is_invocable_v<F&>, "the callback takes the arguments documented "
                                               "for its attach call, or none");
        fn();
    }
}

// The C waitset and the callbacks attached to it.  Attachments hold it weakly: one that
// outlives its waitset detaches nothing.  `mutex` guards the slots' lifetime: attach, detach
// and dispatch take it, the wait itself does not (libln lets other threads attach and detach
// meanwhile).  A slot detached while a batch of events may name it (`busy`, or events left
// over by a callback that threw) goes to the `dead` list, freed once no batch can name it.
struct wait_core {
    static constexpr std::size_t batch = 64;

    ln_waitset* ws = nullptr;
    std::recursive_mutex mutex;
    wait_slot* live = nullptr;
    wait_slot* dead = nullptr;
    bool busy = false;                  // a spin_once is under way
    ln_waitset_event ready[batch] = {}; // written and read by the busy spin_once only
    std::size_t next = 0, end = 0;      // ready[next, end): not dispatched yet
    std::atomic<bool> stop{false};

    wait_core() { check(ln_waitset_create(&ws)); }
    wait_core(const wait_core&) = delete;
    wait_core& operator=(const wait_core&) = delete;
    ~wait_core()
    {
        ln_waitset_destroy(ws);
        free_list(live);
        free_list(dead);
    }

    static void free_list(wait_slot*& head) noexcept
    {
        while (head != nullptr)
            delete std::exchange(head, head->next);
    }
    void link(wait_slot* s) noexcept
    {
        s->next = live;
        if (live != nullptr)
            live->prev = s;
        live = s;
    }
    void detach(wait_slot* s) noexcept
    {
        std::lock_guard<std::recursive_mutex> lock(mutex);
        ln_waitset_detach(ws, s->id);
        if (s->prev != nullptr)
            s->prev->next = s->next;
        else
            live = s->next;
        if (s->next != nullptr)
            s->next->prev = s->prev;
        if (busy || next != end) {
            s->dead = true;
            s->next = dead;
            dead = s;
        } else {
            delete s;
        }
    }
};

} // namespace detail

// A waitset.  Attach what to wait for, each with a callback, then spin() (until stop()) or
// spin_once() from one thread; the callbacks run on that thread, one after the other.
// attach, detach (an attachment's destruction), trigger() and stop() work from any thread;
// a detach from another thread waits for a callback that runs meanwhile to return, so once an
// attachment is destroyed its callback neither runs nor will.  A callback that throws leaves
// spin_once (and spin) with its exception; the events after it in the batch are dispatched by
// the next spin_once.  Destroy the waitset after spin returned; attachments may outlive it.
// Movable, not copyable; a moved-from waitset can only be destroyed or assigned to.
class waitset {
public:
    // One thing attached: detaches when destroyed (or on detach()).  Movable, not copyable.
    class attachment {
    public:
        attachment() = default;
        attachment(attachment&& o) noexcept
            : core_(std::move(o.core_)), slot_(std::exchange(o.slot_, nullptr)),
              id_(std::exchange(o.id_, 0))
        {}
        attachment& operator=(attachment&& o) noexcept
        {
            if (this != &o) {
                detach();
                core_ = std::move(o.core_);
                slot_ = std::exchange(o.slot_, nullptr);
                id_ = std::exchange(o.id_, 0);
            }
            return *this;
        }
        attachment(const attachment&) = delete;
        attachment& operator=(const attachment&) = delete;
        ~attachment() { detach(); }

        void detach() noexcept
        {
            if (slot_ != nullptr) {
                if (auto core = core_.lock())
                    core->detach(slot_);
            }
            core_.reset();
            slot_ = nullptr;
            id_ = 0;
        }
        // The id libln gave it (ln_waitset_event.id), 0 once detached.
        std::uint32_t id() const noexcept { return id_; }
        explicit operator bool() const noexcept { return slot_ != nullptr; }

        // An inport's attachment: its new deadline (seconds, 0: none), counted from now.
        void set_deadline(double seconds)
        {
            auto core = core_.lock();
            if (!core)
                throw error(LN_EBADHANDLE, "set_deadline: the attachment or its waitset is gone");
            check(ln_waitset_set_deadline(core->ws, id_, seconds));
        }

    private:
        friend class waitset;
        attachment(const std::shared_ptr<detail::wait_core>& core, detail::wait_slot* slot)
            : core_(core), slot_(slot), id_(slot->id)
        {}
        std::weak_ptr<detail::wait_core> core_;
        detail::wait_slot* slot_ = nullptr; // freed by the core
        std::uint32_t id_ = 0;
    };

    // What to report of one inport (an inport has one attachment): on_data while it has
    // samples to read (again after each callback that left some unread), on_deadline(missed)
    // when `deadline` seconds passed without a new sample, on_gone / on_back when its topic
    // lost its last publisher / has one again.  Empty callbacks are not asked for.
    template <typename T>
    struct inport_callbacks {
        std::function<void(inport<T>&)> on_data;
        double deadline = 0.0;
        std::function<void(std::uint32_t missed)> on_deadline;
        std::function<void()> on_gone;
        std::function<void()> on_back;
    };

    waitset() : c_(std::make_shared<detail::wait_core>()) {}
    waitset(waitset&&) noexcept = default;
    waitset& operator=(waitset&&) noexcept = default;
    waitset(const waitset&) = delete;
    waitset& operator=(const waitset&) = delete;

    // CLOCK_MONOTONIC in ns, the clock of at() and next_due().
    static std::int64_t monotonic_ns() noexcept
    {
        timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
    }

    // ---- attaching: the inport, block or descriptor stays where it is while attached ----

    // fn(inport<T>&) or fn() while `port` has samples to read: read them in it.
    template <typename T, typename F>
    attachment on_data(inport<T>& port, F fn)
    {
        inport_callbacks<T> cb;
        cb.on_data = [fn = std::move(fn)](inport<T>& p) mutable { detail::call_with(fn, p); };
        return watch(port, std::move(cb));
    }
    // fn(missed) or fn() each time `seconds` pass without a new sample on `port`.
    template <typename T, typename F>
    attachment on_deadline(inport<T>& port, double seconds, F fn)
    {
        inport_callbacks<T> cb;
        cb.deadline = seconds;
        cb.on_deadline = [fn = std::move(fn)](std::uint32_t missed) mutable {
            detail::call_with(fn, missed);
        };
        return watch(port, std::move(cb));
    }
    template <typename T>
    attachment watch(inport<T>& port, inport_callbacks<T> cb)
    {
        std::uint32_t flags = 0;
        if (cb.on_data)
            flags |= LN_WAIT_ON_DATA;
        if (cb.on_gone || cb.on_back || !cb.on_data)
            flags |= LN_WAIT_ON_LIVELINESS; // without data: so that 0 does not mean data
        inport<T>* p = &port;
        double deadline = cb.on_deadline ? cb.deadline : 0.0;
        return attach(
            [p, cb = std::move(cb)](const ln_waitset_event& ev) {
                switch (ev.kind) {
                case LN_WAIT_DATA:
                    if (cb.on_data)
                        cb.on_data(*p);
                    break;
                case LN_WAIT_DEADLINE:
                    if (cb.on_deadline)
                        cb.on_deadline(ev.count);
                    break;
                case LN_WAIT_GONE:
                    if (cb.on_gone)
                        cb.on_gone();
                    break;
                case LN_WAIT_BACK:
                    if (cb.on_back)
                        cb.on_back();
                    break;
                default:
                    break;
                }
            },
            [&](void* user, std::uint32_t* id) {
                return ln_waitset_attach_inport(c_->ws, port.get(), flags, deadline, user, id);
            });
    }

    // The requests of `clnt`'s service group `group` ("": the default): the waitset handles
    // them (the providers' handlers run here), then calls fn(handled) or fn() if given.
    template <typename F>
    attachment on_requests(const client& clnt, const std::string& group, F fn)
    {
        return attach(
            [c = clnt.share(), group, fn = std::move(fn)](const ln_waitset_event&) mutable {
                int n = ln_wait_and_handle_service_group_requests(c.get(), group.c_str(), 0.0);
                if (n == LN_EINTR)
                    n = 0;
                detail::call_with(fn, check(n));
            },
            [&](void* user, std::uint32_t* id) {
                return ln_waitset_attach_service_group(c_->ws, clnt.get(), group.c_str(), user, id);
            });
    }
    attachment on_requests(const client& clnt, const std::string& group = "")
    {
        return on_requests(clnt, group, [] {});
    }
    // fn() when the group a registered provider (or connected event handler) is in has
    // requests; fn handles them, e.g. client::wait_and_handle_service_group_requests(group, 0).
    template <typename T, typename F>
    attachment on_requests(service_provider<T>& provider, F fn)
    {
        return attach([fn = std::move(fn)](const ln_waitset_event&) mutable { fn(); },
                      [&](void* user, std::uint32_t* id) {
                          return ln_waitset_attach_provider(c_->ws, provider.get(), user, id);
                      });
    }
    template <typename T, typename F>
    attachment on_requests(event_handler<T>& handler, F fn)
    {
        return attach([fn = std::move(fn)](const ln_waitset_event&) mutable { fn(); },
                      [&](void* user, std::uint32_t* id) {
                          return ln_waitset_attach_event_handler(c_->ws, handler.get(), user, id);
                      });
    }

    // fn(block) or fn() when overrides arrived for `block`: take them with block.update().
    template <typename F>
    attachment on_parameters(parameters::parameter_block& block, F fn)
    {
        parameters::parameter_block* b = &block;
        return attach(
            [b, fn = std::move(fn)](const ln_waitset_event&) mutable { detail::call_with(fn, *b); },
            [&](void* user, std::uint32_t* id) {
                return ln_waitset_attach_parameter_block(c_->ws, block.get(), user, id);
            });
    }

    // fn(fired) or fn() while `fd` (kept open by the caller) is ready for `events`
    // (LN_WAIT_READABLE and/or LN_WAIT_WRITABLE); fired may also hold LN_WAIT_ERROR.
    template <typename F>
    attachment on_fd(int fd, std::uint32_t events, F fn)
    {
        auto call = [fn = std::move(fn)](const ln_waitset_event& ev) mutable {
            detail::call_with(fn, ev.events);
        };
        return attach(std::move(call), [&](void* user, std::uint32_t* id) {
            return ln_waitset_attach_fd(c_->ws, fd, events, user, id);
        });
    }

    // Timers on absolute times, so they do not drift: fn(count) or fn() at `first_ns`
    // (monotonic_ns(); 0: now + period), then every `period` seconds (0: once only).  count
    // is how many expiries passed since the last call: one that fell behind skips, never
    // bursts.  every(period, fn) starts a period from now.
    template <typename F>
    attachment at(std::int64_t first_ns, double period, F fn)
    {
        auto call = [fn = std::move(fn)](const ln_waitset_event& ev) mutable {
            detail::call_with(fn, ev.count);
        };
        return attach(std::move(call), [&](void* user, std::uint32_t* id) {
            return ln_waitset_attach_timer(c_->ws, first_ns, period, user, id);
        });
    }
    template <typename F>
    attachment every(double period, F fn)
    {
        return at(0, period, std::move(fn));
    }

    // ---- waiting ----

    // Waits up to `timeout` seconds (< 0: until something fires, 0: only what is ready now)
    // and runs the callback of each event; returns how many events it handled (a trigger()
    // counts: it has no callback), 0 when the timeout passed or a signal handler ran.
    // LN_EBUSY while another thread spins, or when called from a callback.
    int spin_once(double timeout = -1.0)
    {
        detail::wait_core& c = *c_;
        {
            std::lock_guard<std::recursive_mutex> lock(c.mutex);
            if (c.busy)
                throw error(LN_EBUSY, "EBUSY: the waitset is spun by another thread or a "
                                      "callback of it");
            c.busy = true;
        }
        struct idle {
            detail::wait_core& c;
            ~idle()
            {
                std::lock_guard<std::recursive_mutex> lock(c.mutex);
                c.busy = false;
                if (c.next == c.end)
                    detail::wait_core::free_list(c.dead);
            }
        } done{c};
        if (c.next == c.end) { // nothing left over: wait
            int n = ln_waitset_wait(c.ws, timeout, c.ready, detail::wait_core::batch);
            if (n == LN_EINTR)
                return 0;
            c.next = 0;
            c.end = static_cast<std::size_t>(check(n));
        }
        std::lock_guard<std::recursive_mutex> lock(c.mutex);
        int handled = 0;
        while (c.next < c.end) {
            const ln_waitset_event& ev = c.ready[c.next++];
            if (ev.kind == LN_WAIT_TRIGGER) {
                handled++;
                continue;
            }
            auto* slot = static_cast<detail::wait_slot*>(ev.user_data);
            if (slot->dead)
                continue;
            handled++;
            slot->fire(ev);
        }
        return handled;
    }
    // spin_once until stop() (also one that came before spin started); returns with the
    // stop taken, so spin can run again.
    void spin()
    {
        while (!c_->stop.exchange(false))
            spin_once(-1.0);
    }
    // Ends spin() from a callback, another thread or a signal handler (async-signal-safe).
    void stop() noexcept
    {
        c_->stop.store(true);
        ln_waitset_trigger(c_->ws);
    }
    // Wakes the waiting thread: its spin_once returns.  Any thread, or a signal handler.
    void trigger() { check(ln_waitset_trigger(c_->ws)); }

    // For another event loop: a descriptor that becomes readable when spin_once(0) may have
    // something to do, and when the next timer or deadline falls due (monotonic_ns(), -1:
    // none).  The descriptor belongs to the waitset.
    int fd() const { return check(ln_waitset_fd(c_->ws)); }
    std::int64_t next_due() const
    {
        std::int64_t ns = -1;
        check(ln_waitset_next_due(c_->ws, &ns));
        return ns;
    }
    ln_waitset* get() const noexcept { return c_->ws; }

private:
    // Makes the slot, attaches it with c_attach(user_data, &id) under the lock (so that no
    // event of it is dispatched before it is listed) and hands out its attachment.
    template <typename F, typename A>
    attachment attach(F fn, A c_attach)
    {
        std::unique_ptr<detail::wait_slot> slot(new detail::wait_slot_of<F>(std::move(fn)));
        std::lock_guard<std::recursive_mutex> lock(c_->mutex);
        std::uint32_t id = 0;
        check(c_attach(static_cast<void*>(slot.get()), &id));
        slot->id = id;
        c_->link(slot.get());
        return attachment(c_, slot.release());
    }

    std::shared_ptr<detail::wait_core> c_;
};

} // namespace ln

#endif // LN_WAITSET_HPP
