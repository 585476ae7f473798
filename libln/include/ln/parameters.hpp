// parameters.hpp — C++17 wrapper of libln's parameter blocks (docs/parameters.md), with the names
// of the original's ln::parameters: a parameter_block of a client, register_parameters() with
// one port_description {"name", "description", &in, &out} per parameter, update() from the loop.
// A parameter's type follows from its variable: arithmetic types, char[N] (a string), T[N] and
// std::array<T, N> of them.  Failures throw ln::error; update() never throws.
#ifndef LN_PARAMETERS_HPP
#define LN_PARAMETERS_HPP

#include <ln/ln.hpp>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace ln {
namespace parameters {

namespace detail {
template <typename T>
struct md_type;
template <>
struct md_type<char> {
    static constexpr const char* name = "char";
};
template <>
struct md_type<std::int8_t> {
    static constexpr const char* name = "int8_t";
};
template <>
struct md_type<std::uint8_t> {
    static constexpr const char* name = "uint8_t";
};
template <>
struct md_type<std::int16_t> {
    static constexpr const char* name = "int16_t";
};
template <>
struct md_type<std::uint16_t> {
    static constexpr const char* name = "uint16_t";
};
template <>
struct md_type<std::int32_t> {
    static constexpr const char* name = "int32_t";
};
template <>
struct md_type<std::uint32_t> {
    static constexpr const char* name = "uint32_t";
};
template <>
struct md_type<std::int64_t> {
    static constexpr const char* name = "int64_t";
};
template <>
struct md_type<std::uint64_t> {
    static constexpr const char* name = "uint64_t";
};
template <>
struct md_type<float> {
    static constexpr const char* name = "float";
};
template <>
struct md_type<double> {
    static constexpr const char* name = "double";
};

// Element type and count of a parameter variable.
template <typename T>
struct shape {
    using element = T;
    static constexpr std::uint32_t count = 1;
};
template <typename T, std::size_t N>
struct shape<T[N]> {
    using element = T;
    static constexpr std::uint32_t count = N;
};
template <typename T, std::size_t N>
struct shape<std::array<T, N>> {
    using element = T;
    static constexpr std::uint32_t count = N;
};
} // namespace detail

constexpr double no_limit = std::numeric_limits<double>::quiet_NaN();

// One parameter: `in` is the program's variable (nullptr: none, the value without an
// override is then *out as it is when registered), `out` what update() writes.  min and max
// (NaN: none) bound every element; a read-only parameter is shown, never overridden.
template <typename T>
struct port_description {
    std::string name;
    std::string description;
    const T* in = nullptr;
    T* out = nullptr;
    double min = no_limit;
    double max = no_limit;
    bool read_only = false;
};
// So that port_description{"kp", "stiffness", &kp_in, &kp, 0.0, 1000.0} needs no <T>.
template <typename T>
port_description(std::string, std::string, const T*, T*) -> port_description<T>;
template <typename T>
port_description(std::string, std::string, const T*, T*, double, double) -> port_description<T>;
template <typename T>
port_description(std::string, std::string, const T*, T*, double, double, bool)
    -> port_description<T>;
template <typename T>
port_description(std::string, std::string, std::nullptr_t, T*) -> port_description<T>;
template <typename T>
port_description(std::string, std::string, std::nullptr_t, T*, double, double)
    -> port_description<T>;
template <typename T>
port_description(std::string, std::string, std::nullptr_t, T*, double, double, bool)
    -> port_description<T>;

class parameter_block {
public:
    // Gets the name of the new value and its bytes (count elements of the parameter's type;
    // value_as<T>() reads them); returns "" to accept it, else the reason it is refused.
    // Runs on libln's service thread.
    using validator = std::function<std::string(const std::string& name, const void* value)>;

    parameter_block(const ln::client& clnt, const std::string& group_name) : c_(clnt.share())
    {
        ln::check(ln_parameter_block_create(c_.get(), &b_, group_name.c_str()));
    }
    parameter_block(const ln::client* clnt, const std::string& group_name)
        : parameter_block(*clnt, group_name)
    {}
    ~parameter_block()
    {
        if (b_ != nullptr)
            ln_parameter_block_destroy(b_);
    }
    // libln keeps a pointer to it (the validator): neither copied nor moved.
    parameter_block(const parameter_block&) = delete;
    parameter_block& operator=(const parameter_block&) = delete;

    // Adds every parameter, then registers the block: callable once.
    template <typename... T>
    void register_parameters(const port_description<T>&... ports)
    {
        (add(ports), ...);
        do_register();
    }
    // The same in steps: add() parameters, then do_register().  add returns the index.
    template <typename T>
    int add(const port_description<T>& p)
    {
        using element = typename detail::shape<T>::element;
        static_assert(std::is_trivially_copyable<T>::value, "parameters are plain values");
        ln_parameter_desc d{};
        d.name = p.name.c_str();
        d.type = detail::md_type<element>::name;
        d.count = detail::shape<T>::count;
        d.description = p.description.c_str();
        d.input = p.in;
        d.output = p.out;
        if (p.min == p.min) { // not NaN
            d.flags |= LN_PARAMETER_MIN;
            d.min = p.min;
        }
        if (p.max == p.max) {
            d.flags |= LN_PARAMETER_MAX;
            d.max = p.max;
        }
        if (p.read_only)
            d.flags |= LN_PARAMETER_READ_ONLY;
        int index = ln::check(ln_parameter_block_add(b_, &d));
        names_.push_back(p.name);
        return index;
    }
    void do_register() { ln::check(ln_parameter_block_register(b_)); }
    // Before registering.
    void set_validator(validator v)
    {
        validator_ = std::move(v);
        ln::check(
            ln_parameter_block_set_validator(b_, validator_ ? &call_validator : nullptr, this));
    }

    // The loop's update point: how many parameters changed (set or reset) since the last one.
    int update() noexcept { return ln_parameter_block_update(b_); }
    bool changed(int index) const noexcept { return ln_parameter_block_changed(b_, index) > 0; }
    bool changed(const std::string& name) const noexcept
    {
        for (std::size_t i = 0; i < names_.size(); i++)
            if (names_[i] == name)
                return changed(static_cast<int>(i));
        return false;
    }
    std::string service_name() const { return ln_parameter_block_service_name(b_); }
    ln_parameter_block* get() const noexcept { return b_; }

    template <typename T>
    static T value_as(const void* value)
    {
        T v;
        std::memcpy(&v, value, sizeof v);
        return v;
    }

private:
    static int call_validator(ln_parameter_block*, int, const char* name, const void* value,
                              char* reason, std::size_t size, void* self)
    {
        std::string why;
        try {
            why = static_cast<parameter_block*>(self)->validator_(name, value);
        } catch (const std::exception& e) {
            why = std::string("validator failed: ") + e.what();
        } catch (...) {
            why = "validator failed";
        }
        if (why.empty())
            return 0;
        std::snprintf(reason, size, "%s", why.c_str());
        return 1;
    }

    ln::detail::client_ptr c_;
    ln_parameter_block* b_ = nullptr;
    validator validator_;
    std::vector<std::string> names_;
};

} // namespace parameters
} // namespace ln

#endif // LN_PARAMETERS_HPP
