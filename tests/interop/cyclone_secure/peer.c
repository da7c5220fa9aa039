/* saw-cyclone-peer: an independent DDS peer (Debian's Cyclone DDS 0.10, C API) for the security
 * tests. Its security, if any, comes from CYCLONEDDS_URI (the Debian build ships the DDS Security
 * plugins), so the same program is an enrolled peer or an outsider.
 *
 *   saw-cyclone-peer read DOMAIN COMPONENT N TIMEOUT_S   reads N samples of rt/COMPONENT/measured_cp
 *   saw-cyclone-peer write DOMAIN COMPONENT SECONDS      writes servo_cf (0, 0, 0.5 N) at 100 Hz
 *
 * Prints one line of figures; exits 0 when the reads arrived (read) or a gateway's reader
 * matched (write), 1 otherwise, 2 on bad arguments or when DDS refused to start (security
 * configuration rejected). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "ros_types.h"

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void sleep_ms(long ms) {
  struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
  nanosleep(&t, NULL);
}

static int usage(void) {
  fprintf(stderr,
          "usage: saw-cyclone-peer read DOMAIN COMPONENT N TIMEOUT_S | write DOMAIN COMPONENT SECONDS\n");
  return 2;
}

/* Reliable and XCDR1, as the gateway's command readers and sawdds use them. */
static dds_qos_t* reliable_qos(void) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 16);
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  return q;
}

/* Topic rt/COMPONENT/WHAT of type `desc`; its name in `name`. Says why when Cyclone refuses it. */
static dds_entity_t component_topic(dds_entity_t dp, const dds_topic_descriptor_t* desc,
                                    const char* component, const char* what, char* name, size_t size) {
  snprintf(name, size, "rt/%s/%s", component, what);
  const dds_entity_t topic = dds_create_topic(dp, desc, name, NULL, NULL);
  if (topic < 0) fprintf(stderr, "saw-cyclone-peer: topic %s: %s\n", name, dds_strretcode(topic));
  return topic;
}

static int read_poses(dds_entity_t dp, const char* component, int wanted, double timeout) {
  char name[256];
  const dds_entity_t topic = component_topic(dp, &geometry_msgs_msg_dds__PoseStamped__desc, component,
                                             "measured_cp", name, sizeof name);
  if (topic < 0) return 2;
  dds_qos_t* q = dds_create_qos(); /* best effort: matches the gateway's state writers */
  dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  dds_entity_t reader = dds_create_reader(dp, topic, q, NULL);
  dds_delete_qos(q);
  if (reader < 0) {
    fprintf(stderr, "saw-cyclone-peer: reader of %s: %s\n", name, dds_strretcode(reader));
    return 2;
  }
  const double start = now_s();
  int got = 0;
  double first = -1;
  while (got < wanted && now_s() - start < timeout) {
    void* samples[16] = {NULL};
    dds_sample_info_t infos[16];
    const int n = dds_take(reader, samples, infos, 16, 16);
    for (int i = 0; i < n; ++i)
      if (infos[i].valid_data) {
        const geometry_msgs_msg_dds__PoseStamped_* p = samples[i];
        if (first < 0) first = now_s() - start;
        if (got == 0)
          printf("first pose: %g %g %g\n", p->pose.position.x, p->pose.position.y, p->pose.position.z);
        ++got;
      }
    if (n > 0) dds_return_loan(reader, samples, n);
    if (n <= 0) sleep_ms(2);
  }
  printf("received %d of %d poses on %s (first after %.3f s)\n", got, wanted, name, first);
  fflush(stdout);
  return got >= wanted ? 0 : 1;
}

static int write_forces(dds_entity_t dp, const char* component, double seconds) {
  char name[256];
  const dds_entity_t topic = component_topic(dp, &geometry_msgs_msg_dds__WrenchStamped__desc, component,
                                             "servo_cf", name, sizeof name);
  if (topic < 0) return 2;
  dds_qos_t* q = reliable_qos();
  dds_entity_t writer = dds_create_writer(dp, topic, q, NULL);
  dds_delete_qos(q);
  if (writer < 0) {
    fprintf(stderr, "saw-cyclone-peer: writer of %s: %s\n", name, dds_strretcode(writer));
    return 2;
  }
  geometry_msgs_msg_dds__WrenchStamped_ w;
  memset(&w, 0, sizeof w);
  w.header.frame_id = "saw-cyclone-peer";
  w.wrench.force.z = 0.5;
  const double start = now_s();
  int written = 0;
  uint32_t matched = 0;
  while (now_s() - start < seconds) {
    dds_publication_matched_status_t st;
    if (dds_get_publication_matched_status(writer, &st) == DDS_RETCODE_OK && st.current_count > matched)
      matched = st.current_count;
    if (dds_write(writer, &w) == DDS_RETCODE_OK) ++written;
    sleep_ms(10);
  }
  printf("wrote %d servo_cf samples on %s; gateway readers matched: %u\n", written, name, matched);
  fflush(stdout);
  return matched > 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  if (argc < 5) return usage();
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[2]);
  const dds_entity_t dp = dds_create_participant(domain, NULL, NULL);
  if (dp < 0) {
    /* With security configured, a certificate or permissions file that Cyclone rejects ends here. */
    fprintf(stderr, "saw-cyclone-peer: no participant in domain %d: %s\n", (int)domain, dds_strretcode(dp));
    return 2;
  }
  int rc;
  if (strcmp(argv[1], "read") == 0 && argc == 6)
    rc = read_poses(dp, argv[3], atoi(argv[4]), atof(argv[5]));
  else if (strcmp(argv[1], "write") == 0 && argc == 5)
    rc = write_forces(dp, argv[3], atof(argv[4]));
  else
    rc = usage();
  dds_delete(dp);
  return rc;
}
