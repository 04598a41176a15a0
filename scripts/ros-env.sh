# Keeps DDS discovery on loopback (nothing leaves this machine) and picks a domain id of this
# shell's own unless one is set.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
if [ -z "${ROS_DOMAIN_ID:-}" ]; then
  # 1..101 keeps Fast DDS port numbers valid.
  export ROS_DOMAIN_ID=$(( ($$ % 101) + 1 ))
fi
