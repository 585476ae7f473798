/* test_generated_layout_cpp.cpp — the C++ header ln_generate makes has exactly the layout
 * and constants of the C header for the same mds, so C and C++ processes can share
 * messages; both headers are included into this one program and compared. */
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

#include <ln/ln.h>

#include "ln_test.h"
#include "robot_messages.h"
#include "robot_messages.hpp"

#define CHECK_SAME_FIELD(c_type, cpp_type, field)                                                  \
    do {                                                                                           \
        LN_CHECK_EQ(offsetof(c_type, field), offsetof(cpp_type, field));                           \
        LN_CHECK_EQ(sizeof(c_type::field), sizeof(cpp_type::field));                               \
    } while (0)

#define CHECK_SAME_STRING(a, b) LN_CHECK(std::string(a) == std::string(b))

static void test_joint_state(void)
{
    LN_CHECK_EQ(sizeof(robot_joint_state_t), sizeof(robot::joint_state_t));
    CHECK_SAME_FIELD(robot_joint_state_t, robot::joint_state_t, timestamp);
    CHECK_SAME_FIELD(robot_joint_state_t, robot::joint_state_t, cycle);
    CHECK_SAME_FIELD(robot_joint_state_t, robot::joint_state_t, position);
    CHECK_SAME_FIELD(robot_joint_state_t, robot::joint_state_t, velocity);
    CHECK_SAME_FIELD(robot_joint_state_t, robot::joint_state_t, effort);
    CHECK_SAME_STRING(robot::joint_state_md_name, ROBOT_JOINT_STATE_MD_NAME);
    CHECK_SAME_STRING(robot::joint_state_signature, ROBOT_JOINT_STATE_SIGNATURE);
    LN_CHECK(robot::joint_state_layout_hash == ROBOT_JOINT_STATE_LAYOUT_HASH);
}

static void test_command(void)
{
    LN_CHECK_EQ(sizeof(robot_command_t), sizeof(robot::command_t));
    CHECK_SAME_FIELD(robot_command_t, robot::command_t, mode);
    CHECK_SAME_FIELD(robot_command_t, robot::command_t, target);
    CHECK_SAME_FIELD(robot_command_t, robot::command_t, max_velocity);
    CHECK_SAME_STRING(robot::command_md_name, ROBOT_COMMAND_MD_NAME);
    CHECK_SAME_STRING(robot::command_signature, ROBOT_COMMAND_SIGNATURE);
    LN_CHECK(robot::command_layout_hash == ROBOT_COMMAND_LAYOUT_HASH);
}

static void test_nested_types(void)
{
    LN_CHECK_EQ(sizeof(robot_pose_t), sizeof(robot::pose_t));
    LN_CHECK_EQ(sizeof(robot_tool_state_t), sizeof(robot::tool_state_t));
    CHECK_SAME_FIELD(robot_tool_state_t, robot::tool_state_t, tool);
    CHECK_SAME_FIELD(robot_tool_state_t, robot::tool_state_t, stiffness);
    CHECK_SAME_FIELD(robot_tool_state_t, robot::tool_state_t, gripper_closed);
    LN_CHECK_EQ(sizeof(ln_time_t), sizeof(ln::time_t));
    CHECK_SAME_FIELD(ln_string_t, ln::string_t, data_len);
    CHECK_SAME_FIELD(ln_string_t, ln::string_t, data);
    CHECK_SAME_STRING(robot::tool_state_md_name, ROBOT_TOOL_STATE_MD_NAME);
    LN_CHECK(robot::tool_state_layout_hash == ROBOT_TOOL_STATE_LAYOUT_HASH);
}

static void test_service(void)
{
    using request = decltype(robot::set_gains_t::req);
    using response = decltype(robot::set_gains_t::resp);
    LN_CHECK_EQ(sizeof(robot_set_gains_t), sizeof(robot::set_gains_t));
    CHECK_SAME_FIELD(robot_set_gains_t, robot::set_gains_t, req);
    CHECK_SAME_FIELD(robot_set_gains_t, robot::set_gains_t, resp);
    CHECK_SAME_FIELD(robot_set_gains_request_t, request, kd);
    CHECK_SAME_FIELD(robot_set_gains_request_t, request, profile_name_len);
    CHECK_SAME_FIELD(robot_set_gains_request_t, request, profile_name);
    CHECK_SAME_FIELD(robot_set_gains_response_t, response, ok);
    CHECK_SAME_FIELD(robot_set_gains_response_t, response, message);
    CHECK_SAME_STRING(robot::set_gains_md_name, ROBOT_SET_GAINS_MD_NAME);
    CHECK_SAME_STRING(robot::set_gains_signature, ROBOT_SET_GAINS_SIGNATURE);
    LN_CHECK(robot::set_gains_layout_hash == ROBOT_SET_GAINS_LAYOUT_HASH);
}

/* Service types have md_traits too, with what ln_get_service takes and the section types. */
static void test_service_traits(void)
{
    using traits = ln::md_traits<robot::set_gains_t>;
    static_assert(std::is_same_v<traits::request_type, robot::set_gains_t::request_t>);
    static_assert(std::is_same_v<traits::response_type, robot::set_gains_t::response_t>);
    static_assert(traits::layout_hash == ROBOT_SET_GAINS_LAYOUT_HASH);
    CHECK_SAME_STRING(traits::md_name, ROBOT_SET_GAINS_MD_NAME);
    CHECK_SAME_STRING(traits::signature, ROBOT_SET_GAINS_SIGNATURE);
    using plan = ln::md_traits<robot::plan_path_t>;
    static_assert(std::is_same_v<plan::response_type, robot::plan_path_t::response_t>);
    CHECK_SAME_STRING(plan::signature, ROBOT_PLAN_PATH_SIGNATURE);
}

/* ln.h is usable from C++ as is: extern "C" linkage, the enum, the version macros. */
static void test_ln_h_from_cpp(void)
{
    LN_CHECK_EQ(LN_VERSION_CHECK(), LN_OK);
    LN_CHECK(std::string(ln_error_name(LN_ETIMEOUT)) == "ETIMEOUT");
}

int main()
{
    LN_TEST_RUN(test_ln_h_from_cpp);
    LN_TEST_RUN(test_joint_state);
    LN_TEST_RUN(test_command);
    LN_TEST_RUN(test_nested_types);
    LN_TEST_RUN(test_service);
    LN_TEST_RUN(test_service_traits);
    LN_TEST_EXIT();
}
