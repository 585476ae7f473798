// ln.hpp — header-only C++17 RAII wrapper of libln for C++ controllers.
// Failures throw ln::error carrying the LN_E* code; a timed-out read returns false instead,
// since timeouts are ordinary control flow in a control loop.  Ports keep their client alive.
#ifndef LN_LN_HPP
#define LN_LN_HPP

#include <ln/ln.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace ln {

// md name and layout hash of a generated message type; ln_generate's C++ headers specialise it.
template <typename T> struct md_traits;

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

template <typename T> class outport;
template <typename T> class inport;

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
    std::string name() const { return ln_client_name(c_.get()); }

    template <typename T> outport<T> publish(const std::string& topic, unsigned flags = 0)
    {
        return outport<T>(c_, topic, md_traits<T>::md_name, md_traits<T>::layout_hash, flags);
    }
    template <typename T> inport<T> subscribe(const std::string& topic, unsigned buffers = 1)
    {
        return inport<T>(c_, topic, md_traits<T>::md_name, md_traits<T>::layout_hash, buffers);
    }

private:
    detail::client_ptr c_;
};

template <typename T> class outport {
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

template <typename T> class inport {
    static_assert(std::is_trivially_copyable<T>::value, "messages are plain packed structs");

public:
    inport(detail::client_ptr c, const std::string& topic, const char* md_name,
           std::uint64_t layout_hash, unsigned buffers = 1)
        : c_(std::move(c))
    {
        ln_port_options opts;
        ln_port_options_init(&opts);
        opts.buffers = buffers;
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

}  // namespace ln

#endif  // LN_LN_HPP
