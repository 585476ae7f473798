/* test_generated_layout.c — the C header ln_generate makes from the robot/ and ln/ mds has
 * the one packed layout the md files define (offsets and sizes worked out by hand here) and
 * the per-md constants the generator promises, including NAME_SERVICE as the argument list of
 * ln_get_service. */
#include <stddef.h>
#include <stdint.h>

#include "ln_test.h"
#include "robot_messages.h"

static void test_joint_state(void)
{
    LN_CHECK_EQ(offsetof(robot_joint_state_t, timestamp), 0);
    LN_CHECK_EQ(offsetof(robot_joint_state_t, cycle), 8);
    LN_CHECK_EQ(offsetof(robot_joint_state_t, position), 12);
    LN_CHECK_EQ(offsetof(robot_joint_state_t, velocity), 12 + 7 * 8);
    LN_CHECK_EQ(offsetof(robot_joint_state_t, effort), 12 + 14 * 8);
    LN_CHECK_EQ(sizeof(robot_joint_state_t), 12 + 21 * 8);
    LN_CHECK_EQ(ROBOT_JOINT_STATE_SIZE, sizeof(robot_joint_state_t));
    LN_CHECK_STREQ(ROBOT_JOINT_STATE_MD_NAME, "robot/joint_state");
    LN_CHECK(ROBOT_JOINT_STATE_SIGNATURE[0] != '\0');
}

static void test_command(void)
{
    LN_CHECK_EQ(offsetof(robot_command_t, mode), 8);
    LN_CHECK_EQ(offsetof(robot_command_t, target), 9);
    LN_CHECK_EQ(offsetof(robot_command_t, max_velocity), 9 + 7 * 8);
    LN_CHECK_EQ(sizeof(robot_command_t), 9 + 14 * 8);
    LN_CHECK_EQ(ROBOT_COMMAND_SIZE, sizeof(robot_command_t));
    LN_CHECK_STREQ(ROBOT_COMMAND_MD_NAME, "robot/command");
}

static void test_layout_hashes_differ(void)
{
    uint64_t joint_state = ROBOT_JOINT_STATE_LAYOUT_HASH, command = ROBOT_COMMAND_LAYOUT_HASH;
    LN_CHECK(joint_state != command);
    LN_CHECK(joint_state != 0 && command != 0);
    LN_CHECK(strcmp(ROBOT_JOINT_STATE_SIGNATURE, ROBOT_COMMAND_SIGNATURE) != 0);
}

static void test_nested_types(void)
{
    LN_CHECK_EQ(sizeof(robot_pose_t), 7 * 8);
    LN_CHECK_EQ(offsetof(robot_tool_state_t, tool), sizeof(robot_pose_t));
    LN_CHECK_EQ(offsetof(robot_tool_state_t, stiffness), 2 * sizeof(robot_pose_t));
    LN_CHECK_EQ(offsetof(robot_tool_state_t, gripper_closed), 2 * 7 * 8 + 36 * 8);
    LN_CHECK_EQ(sizeof(robot_tool_state_t), 2 * 7 * 8 + 36 * 8 + 1);
    LN_CHECK_EQ(offsetof(ln_time_t, nsec), 8);
    LN_CHECK_EQ(sizeof(ln_time_t), 12);
}

static void test_dynamic_fields(void)
{
    LN_CHECK_EQ(offsetof(ln_string_t, data_len), 0);
    LN_CHECK_EQ(offsetof(ln_string_t, data), 4);
    LN_CHECK_EQ(sizeof(((ln_string_t*)0)->data_len), 4);
    LN_CHECK_EQ(sizeof(ln_string_t), 4 + sizeof(char*));
}

static void test_service(void)
{
    LN_CHECK_EQ(offsetof(robot_set_gains_request_t, kd), 7 * 8);
    LN_CHECK_EQ(offsetof(robot_set_gains_request_t, profile_name_len), 14 * 8);
    LN_CHECK_EQ(offsetof(robot_set_gains_request_t, profile_name), 14 * 8 + 4);
    LN_CHECK_EQ(sizeof(robot_set_gains_request_t), 14 * 8 + 4 + sizeof(char*));
    LN_CHECK_EQ(offsetof(robot_set_gains_response_t, message_len), 1);
    LN_CHECK_EQ(sizeof(robot_set_gains_response_t), 1 + 4 + sizeof(char*));
    LN_CHECK_EQ(offsetof(robot_set_gains_t, resp), sizeof(robot_set_gains_request_t));
    LN_CHECK_EQ(offsetof(robot_plan_path_response_t, status), 4 + sizeof(void*));
    LN_CHECK_STREQ(ROBOT_SET_GAINS_MD_NAME, "robot/set_gains");
}

/* Stands in for ln_get_service's (md name, layout hash, signature) parameters. */
static int service_arguments(const char* md_name, uint64_t layout_hash, const char* signature)
{
    LN_CHECK(layout_hash != 0);
    return strcmp(md_name, ROBOT_SET_GAINS_MD_NAME) == 0 &&
           layout_hash == ROBOT_SET_GAINS_LAYOUT_HASH &&
           strcmp(signature, ROBOT_SET_GAINS_SIGNATURE) == 0;
}

static void test_service_arguments(void)
{
    LN_CHECK(service_arguments(ROBOT_SET_GAINS_SERVICE));
    LN_CHECK(!service_arguments(ROBOT_PLAN_PATH_SERVICE));
    LN_CHECK(strchr(ROBOT_SET_GAINS_SIGNATURE, '|') != NULL);
}

int main(void)
{
    LN_TEST_RUN(test_joint_state);
    LN_TEST_RUN(test_command);
    LN_TEST_RUN(test_layout_hashes_differ);
    LN_TEST_RUN(test_nested_types);
    LN_TEST_RUN(test_dynamic_fields);
    LN_TEST_RUN(test_service);
    LN_TEST_RUN(test_service_arguments);
    LN_TEST_EXIT();
}
