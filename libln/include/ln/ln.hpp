// ln.hpp — header-only C++17 RAII wrapper of libln for C++ controllers.
// Failures throw ln::error carrying the LN_E* code; a timed-out read returns false instead,
// since timeouts are ordinary control flow in a control loop.  Ports, services and providers
// keep their client alive.
#ifndef LN_LN_HPP
#define LN_LN_HPP

#include <ln/ln.h>

#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace ln {

// md name and layout hash of a generated message type, plus signature, request_type and
// response_type for a service type, signature, connect_type and call_type for an event type;
// ln_generate's C++ headers specialise it.
template <typename T>
struct md_traits;

class error : public std::runtime_error {
public:
    error(int code, const std::string& what) : std::runtime_error(what), code_(code) {}
    int code() const noexcept { return code_; }
    const char* name() const noexcept { return ln_error_name(code_); }

private:
    int code_;
};

inline int check(int rc)
{
    if (rc < 0)
        throw error(rc, std::string(ln_error_name(rc) ? ln_error_name(rc) : "?") + ": " +
                            ln_last_error());
    return rc;
}

namespace detail {
using client_ptr = std::shared_ptr<ln_client>;
}

template <typename T>
class outport;
template <typename T>
class inport;
template <typename T>
class service;
template <typename T>
class service_provider;
template <typename T>
class event;
template <typename T>
class event_handler;

class client {
public:
    // Connects to the manager (from `manager`, else -ln_manager in argv, else $LN_MANAGER).
    explicit client(const std::string& name, int argc = 0, char** argv = nullptr,
                    const char* manager = nullptr, double timeout = 10.0)
    {
        ln_client_options opts;
        ln_client_options_init(&opts);
        opts.manager = manager;
        opts.argc = argc;
        opts.argv = argv;
        opts.timeout = timeout;
        ln_client* raw = nullptr;
        check(ln_client_create(&raw, name.c_str(), &opts));
        c_ = detail::client_ptr(raw, [](ln_client* c) { ln_client_destroy(c); });
    }

    ln_client* get() const noexcept { return c_.get(); }
    // Shared ownership of the connection, for wrappers that must keep it alive
    // (ln/parameters.hpp).
    detail::client_ptr share() const noexcept { return c_; }
    std::string name() const { return ln_client_name(c_.get()); }

    // A log line for the manager (ln.h, ln_log): never blocks; false when the queue was full
    // and the line was dropped (counted).  file/line default to the caller's (GCC, Clang).
    bool log(int level, const std::string& text, const char* file = __builtin_FILE(),
             int line = __builtin_LINE())
    {
        int rc = ln_log_text(c_.get(), level, file, line, nullptr, text.c_str());
        if (rc == LN_EAGAIN)
            return false;
        check(rc);
        return true;
    }

    // The replay clock: after use_clock(), now() follows the ln_play --clock on `topic`
    // ("" = "ln.clock"); before that it is CLOCK_REALTIME.  ns since the epoch; 0 before the
    // first clock sample.  Never blocks (ln.h, ln_now).
    void use_clock(const std::string& topic = "")
    {
        check(ln_client_use_clock(c_.get(), topic.empty() ? nullptr : topic.c_str()));
    }
    int64_t now() const
    {
        int64_t ns = 0;
        check(ln_now(c_.get(), &ns));
        return ns;
    }

    template <typename T>
    outport<T> publish(const std::string& topic, unsigned flags = 0)
    {
        return outport<T>(c_, topic, md_traits<T>::md_name, md_traits<T>::layout_hash, flags);
    }
    // flags: LN_SUBSCRIBE_UDP or LN_SUBSCRIBE_TCP to choose how samples of a publisher on
    // another host reach this one (0: the topic's setting).
    template <typename T>
    inport<T> subscribe(const std::string& topic, unsigned buffers = 1, unsigned flags = 0)
    {
        return inport<T>(c_, topic, md_traits<T>::md_name, md_traits<T>::layout_hash, buffers,
                         flags);
    }

    // Services: T is a generated service type (e.g. robot::set_gains_t).
    template <typename T>
    service<T> get_service(const std::string& name)
    {
        return service<T>(c_, name);
    }
    // The handler gets a service_provider<T>::call; see there.  The provider is registered in
    // `group` ("" = default) and serves until it is destroyed.
    template <typename T>
    std::unique_ptr<service_provider<T>>
    provide_service(const std::string& name,
                    std::function<void(typename service_provider<T>::call&)> handler,
                    const std::string& group = "")
    {
        return std::unique_ptr<service_provider<T>>(
            new service_provider<T>(c_, name, std::move(handler), group));
    }
    // Number of requests handled (0 if none came within the timeout).
    int wait_and_handle_service_group_requests(const std::string& group, double timeout)
    {
        return check(ln_wait_and_handle_service_group_requests(c_.get(), group.c_str(), timeout));
    }
    void handle_service_group_in_thread_pool(const std::string& group, const std::string& pool)
    {
        check(ln_handle_service_group_in_thread_pool(c_.get(), group.c_str(), pool.c_str()));
    }
    void set_max_threads(const std::string& pool, unsigned max_threads)
    {
        check(ln_set_max_threads(c_.get(), pool.c_str(), max_threads));
    }

    // Events (docs/events.md): T is a generated event type (e.g. robot::fault_event_t).
    template <typename T>
    event<T> get_event(const std::string& name)
    {
        return event<T>(c_, name);
    }
    // The handler gets an event_handler<T>::call; it is connected with `connect` in `group`
    // ("" = default) and receives calls until it is destroyed.
    template <typename T>
    std::unique_ptr<event_handler<T>>
    connect_event(const std::string& name, const typename md_traits<T>::connect_type& connect,
                  std::function<void(typename event_handler<T>::call&)> handler,
                  const std::string& group = "")
    {
        return std::unique_ptr<event_handler<T>>(
            new event_handler<T>(c_, name, connect, std::move(handler), group));
    }

private:
    detail::client_ptr c_;
};

template <typename T>
class outport {
    static_assert(std::is_trivially_copyable<T>::value, "messages are plain packed structs");

public:
    outport(detail::client_ptr c, const std::string& topic, const char* md_name,
            std::uint64_t layout_hash, unsigned flags = 0)
        : c_(std::move(c))
    {
        ln_port_options opts;
        ln_port_options_init(&opts);
        opts.flags = flags;
        check(ln_publish(c_.get(), &p_, topic.c_str(), md_name, layout_hash, sizeof(T), &opts));
    }
    outport(outport&& o) noexcept : c_(std::move(o.c_)), p_(std::exchange(o.p_, nullptr)) {}
    outport& operator=(outport&& o) noexcept
    {
        std::swap(c_, o.c_);
        std::swap(p_, o.p_);
        return *this;
    }
    outport(const outport&) = delete;
    outport& operator=(const outport&) = delete;
    ~outport()
    {
        if (p_)
            ln_unpublish(p_);
    }

    void write(const T& msg, double timeout = -1.0)
    {
        check(ln_write(p_, &msg, sizeof(T), timeout));
    }

    // A zero-copy slot: fill *it, then commit(); destroyed uncommitted, it publishes nothing.
    class loan {
    public:
        loan(ln_outport* p, T* msg) : p_(p), msg_(msg) {}
        loan(loan&& o) noexcept : p_(std::exchange(o.p_, nullptr)), msg_(o.msg_) {}
        loan(const loan&) = delete;
        loan& operator=(const loan&) = delete;
        ~loan()
        {
            if (p_)
                ln_write_abort(p_);
        }
        T* operator->() const noexcept { return msg_; }
        T& operator*() const noexcept { return *msg_; }
        void commit() { check(ln_write_commit(std::exchange(p_, nullptr))); }

    private:
        ln_outport* p_;
        T* msg_;
    };

    loan borrow_slot(double timeout = -1.0)
    {
        void* data = nullptr;
        check(ln_write_loan(p_, &data, timeout));
        return loan(p_, static_cast<T*>(data));
    }

    int subscriber_count() const { return check(ln_outport_subscriber_count(p_)); }
    ln_outport* get() const noexcept { return p_; }

private:
    detail::client_ptr c_;
    ln_outport* p_ = nullptr;
};

template <typename T>
class inport {
    static_assert(std::is_trivially_copyable<T>::value, "messages are plain packed structs");

public:
    inport(detail::client_ptr c, const std::string& topic, const char* md_name,
           std::uint64_t layout_hash, unsigned buffers = 1, unsigned flags = 0)
        : c_(std::move(c))
    {
        ln_port_options opts;
        ln_port_options_init(&opts);
        opts.buffers = buffers;
        opts.flags = flags;
        check(ln_subscribe(c_.get(), &p_, topic.c_str(), md_name, layout_hash, sizeof(T), &opts));
    }
    inport(inport&& o) noexcept : c_(std::move(o.c_)), p_(std::exchange(o.p_, nullptr)) {}
    inport& operator=(inport&& o) noexcept
    {
        std::swap(c_, o.c_);
        std::swap(p_, o.p_);
        return *this;
    }
    inport(const inport&) = delete;
    inport& operator=(const inport&) = delete;
    ~inport()
    {
        if (p_)
            ln_unsubscribe(p_);
    }

    // false if no sample came within the timeout (0: none available now); throws otherwise.
    bool read(T& msg, double timeout = -1.0, ln_sample_info* info = nullptr)
    {
        int rc = ln_read(p_, &msg, sizeof(T), timeout, info);
        if (rc == LN_ETIMEOUT || rc == LN_EAGAIN)
            return false;
        check(rc);
        return true;
    }

    // A zero-copy view of a sample in the ring; release() says whether it stayed intact.
    class borrowed {
    public:
        borrowed(ln_inport* p, const T* msg) : p_(p), msg_(msg) {}
        borrowed(borrowed&& o) noexcept : p_(std::exchange(o.p_, nullptr)), msg_(o.msg_) {}
        borrowed(const borrowed&) = delete;
        borrowed& operator=(const borrowed&) = delete;
        ~borrowed()
        {
            if (p_)
                ln_read_release(p_);
        }
        explicit operator bool() const noexcept { return msg_ != nullptr; }
        const T* operator->() const noexcept { return msg_; }
        const T& operator*() const noexcept { return *msg_; }
        // true if no publisher overwrote the sample while it was borrowed.
        bool release()
        {
            if (!p_)
                return true;
            int rc = ln_read_release(std::exchange(p_, nullptr));
            if (rc == LN_EOVERRUN)
                return false;
            check(rc);
            return true;
        }

    private:
        ln_inport* p_;
        const T* msg_;
    };

    // An empty `borrowed` (false) if no sample came within the timeout.
    borrowed borrow(double timeout = -1.0, ln_sample_info* info = nullptr)
    {
        const void* data = nullptr;
        int rc = ln_read_borrow(p_, &data, timeout, info);
        if (rc == LN_ETIMEOUT || rc == LN_EAGAIN)
            return borrowed(nullptr, nullptr);
        check(rc);
        return borrowed(p_, static_cast<const T*>(data));
    }

    int publisher_count() const { return check(ln_inport_publisher_count(p_)); }
    std::uint64_t overruns() const { return ln_inport_overruns(p_); }
    ln_inport* get() const noexcept { return p_; }

private:
    detail::client_ptr c_;
    ln_inport* p_ = nullptr;
};

// A caller: fill req, call(), read resp.  Dynamic fields of resp point into memory of this
// object until the next call.  Failures (including a provider's error text, LN_ESERVICE, and
// a timeout) throw ln::error.  Movable, not copyable.
template <typename T>
class service {
    using traits = md_traits<T>;

public:
    using request_type = typename traits::request_type;
    using response_type = typename traits::response_type;

    request_type req{};
    response_type resp{};

    service(detail::client_ptr c, const std::string& name) : c_(std::move(c))
    {
        check(ln_get_service(c_.get(), &s_, name.c_str(), traits::md_name, traits::layout_hash,
                             traits::signature));
    }
    service(service&& o) noexcept
        : req(o.req), resp(o.resp), c_(std::move(o.c_)), s_(std::exchange(o.s_, nullptr))
    {}
    service& operator=(service&& o) noexcept
    {
        if (this != &o) {
            release();
            req = o.req;
            resp = o.resp;
            c_ = std::move(o.c_);
            s_ = std::exchange(o.s_, nullptr);
        }
        return *this;
    }
    service(const service&) = delete;
    service& operator=(const service&) = delete;
    ~service() { release(); }

    // timeout in seconds, < 0 waits forever.
    void call(double timeout = -1) { check(ln_service_call(s_, &req, &resp, timeout)); }
    void set_max_size(std::size_t bytes) { check(ln_service_set_max_size(s_, bytes)); }
    ln_service* get() const noexcept { return s_; }

private:
    void release() noexcept
    {
        if (s_ != nullptr)
            ln_service_release(s_);
        s_ = nullptr;
    }
    detail::client_ptr c_;
    ln_service* s_ = nullptr;
};

// A provider.  The handler gets a `call` with the decoded request (`req`) and a response to
// fill (`resp`).  Returning normally sends resp unless the handler already answered with
// respond() or respond_error(); an exception answers an error with its what() text.  Handlers
// run on the thread that handles the group (wait_and_handle_service_group_requests or a pool).
// Not movable: libln holds a pointer to it.
template <typename T>
class service_provider {
    using traits = md_traits<T>;

public:
    using request_type = typename traits::request_type;
    using response_type = typename traits::response_type;

    class call {
    public:
        request_type req{};
        response_type resp{};

        void respond()
        {
            check(ln_service_request_respond(r_, &resp));
            answered_ = true;
        }
        void respond_error(const std::string& text)
        {
            check(ln_service_request_respond_error(r_, text.c_str()));
            answered_ = true;
        }
        bool answered() const noexcept { return answered_; }

    private:
        friend class service_provider;
        explicit call(ln_service_request* r) : r_(r) {}
        ln_service_request* r_;
        bool answered_ = false;
    };

    service_provider(detail::client_ptr c, const std::string& name,
                     std::function<void(call&)> handler, const std::string& group)
        : c_(std::move(c)), handler_(std::move(handler))
    {
        check(ln_get_service_provider(c_.get(), &p_, name.c_str(), traits::md_name,
                                      traits::layout_hash, traits::signature));
        try {
            check(ln_service_provider_set_handler(p_, &trampoline, this));
            check(ln_service_provider_register(p_, group.c_str()));
        } catch (...) {
            ln_unregister_service_provider(p_);
            throw;
        }
    }
    service_provider(const service_provider&) = delete;
    service_provider& operator=(const service_provider&) = delete;
    ~service_provider() { ln_unregister_service_provider(p_); }

    ln_service_provider* get() const noexcept { return p_; }

private:
    static int trampoline(ln_client*, ln_service_request* r, void* self)
    {
        auto* p = static_cast<service_provider*>(self);
        call c(r);
        try {
            check(ln_service_request_get_data(r, &c.req));
            p->handler_(c);
            if (!c.answered())
                c.respond();
        } catch (const std::exception& e) {
            if (!c.answered())
                ln_service_request_respond_error(r, e.what());
        } catch (...) {
            if (!c.answered())
                ln_service_request_respond_error(r, "handler threw a non-standard exception");
        }
        return 0;
    }
    detail::client_ptr c_;
    std::function<void(call&)> handler_;
    ln_service_provider* p_ = nullptr;
};

// An event caller (docs/events.md): call() sends a call struct to every handler connected
// at that moment and returns how many received it; results() says what happened at each.
// Failures of the call as a whole throw ln::error.  Movable, not copyable.
template <typename T>
class event {
    using traits = md_traits<T>;

public:
    using connect_type = typename traits::connect_type;
    using call_type = typename traits::call_type;
    using filter_type = std::function<bool(const connect_type&)>;

    struct result {
        std::string handler, client;
        int code;                    // LN_OK: received
        std::string error;           // why not
        const connect_type* connect; // valid until the next call
        const call_type* reply;      // nullptr without a reply; valid until the next call
    };

    event(detail::client_ptr c, const std::string& name)
        : c_(std::move(c)), filter_(new filter_type())
    {
        check(ln_get_event(c_.get(), &e_, name.c_str(), traits::md_name, traits::layout_hash,
                           traits::signature));
    }
    event(event&& o) noexcept
        : c_(std::move(o.c_)), e_(std::exchange(o.e_, nullptr)), filter_(std::move(o.filter_))
    {}
    event& operator=(event&& o) noexcept
    {
        if (this != &o) {
            release();
            c_ = std::move(o.c_);
            e_ = std::exchange(o.e_, nullptr);
            filter_ = std::move(o.filter_);
        }
        return *this;
    }
    event(const event&) = delete;
    event& operator=(const event&) = delete;
    ~event() { release(); }

    // timeout in seconds for the whole call, < 0 waits forever.
    int call(const call_type& data, double timeout = -1)
    {
        return check(ln_event_call(e_, &data, timeout));
    }
    // Only handlers whose connect struct `f` accepts get the calls; an empty f: all of them.
    void set_filter(filter_type f)
    {
        *filter_ = std::move(f);
        check(ln_event_set_filter(e_, *filter_ ? &filter_trampoline : nullptr, filter_.get()));
    }
    std::vector<result> results() const
    {
        std::vector<result> out;
        int n = check(ln_event_result_count(e_));
        for (int i = 0; i < n; i++) {
            ln_event_result r;
            check(ln_event_get_result(e_, static_cast<std::size_t>(i), &r));
            out.push_back(result{r.handler, r.client, r.code, r.error,
                                 static_cast<const connect_type*>(r.connect),
                                 static_cast<const call_type*>(r.reply)});
        }
        return out;
    }
    ln_event* get() const noexcept { return e_; }

private:
    static int filter_trampoline(const void* connect, void* f)
    {
        try {
            return (*static_cast<filter_type*>(f))(*static_cast<const connect_type*>(connect)) ? 1
                                                                                               : 0;
        } catch (...) {
            return LN_EINVAL; // the call stops, nothing is sent
        }
    }
    void release() noexcept
    {
        if (e_ != nullptr)
            ln_event_release(e_);
        e_ = nullptr;
    }
    detail::client_ptr c_;
    ln_event* e_ = nullptr;
    std::unique_ptr<filter_type> filter_;
};

// A connected event handler.  The handler gets a `call` with the decoded call struct
// (`data`); it may reply() with a call struct or reply_error(); returning without either
// delivers the call without a reply, an exception answers an error with its what() text.
// Handlers run on the thread that handles the group.  Not movable: libln holds a pointer to it.
template <typename T>
class event_handler {
    using traits = md_traits<T>;

public:
    using connect_type = typename traits::connect_type;
    using call_type = typename traits::call_type;

    class call {
    public:
        call_type data{};

        void reply(const call_type& r)
        {
            check(ln_event_request_reply(r_, &r));
            answered_ = true;
        }
        void reply_error(const std::string& text)
        {
            check(ln_event_request_reply_error(r_, text.c_str()));
            answered_ = true;
        }
        bool answered() const noexcept { return answered_; }
        std::string event_name() const { return ln_event_request_event_name(r_); }

    private:
        friend class event_handler;
        explicit call(ln_event_request* r) : r_(r) {}
        ln_event_request* r_;
        bool answered_ = false;
    };

    event_handler(detail::client_ptr c, const std::string& name, const connect_type& connect,
                  std::function<void(call&)> handler, const std::string& group)
        : c_(std::move(c)), handler_(std::move(handler))
    {
        check(ln_event_connect(c_.get(), &h_, name.c_str(), traits::md_name, traits::layout_hash,
                               traits::signature, &connect, &trampoline, this, group.c_str()));
    }
    event_handler(const event_handler&) = delete;
    event_handler& operator=(const event_handler&) = delete;
    ~event_handler() { ln_event_disconnect(h_); }

    std::string name() const { return ln_event_handler_name(h_); }
    ln_event_handler* get() const noexcept { return h_; }

private:
    static int trampoline(ln_client*, ln_event_request* r, void* self)
    {
        auto* h = static_cast<event_handler*>(self);
        call c(r);
        try {
            check(ln_event_request_get_data(r, &c.data));
            h->handler_(c);
        } catch (const std::exception& e) {
            if (!c.answered())
                ln_event_request_reply_error(r, e.what());
        } catch (...) {
            if (!c.answered())
                ln_event_request_reply_error(r, "handler threw a non-standard exception");
        }
        return 0;
    }
    detail::client_ptr c_;
    std::function<void(call&)> handler_;
    ln_event_handler* h_ = nullptr;
};

} // namespace ln

#endif // LN_LN_HPP
