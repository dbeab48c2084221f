/*
 * cdpr_sim: run the CDPR link firmware on an emulated ATmega2560 (simavr) and play its hardware.
 *
 *   cdpr_sim FIRMWARE.elf
 *
 * USART0 is bridged to a pseudo-terminal; the host talks to it with pyserial. The bridge runs in the
 * emulation thread (simavr's uart_pty part flushes host bytes into the UART only every 1 ms of emulated
 * time and polls for output every 0.5 ms, which would triple the round trip): host bytes enter the UART
 * one per byte time (11 us at 1 Mbaud, like a real line), firmware bytes leave at once.
 * The harness counts STEP pulses (PA0..5) with the DIR levels (PC0..5) into cable positions, feeds the
 * six ADC inputs from a tension model (a cable hauled in stretches a spring), and paces emulation to
 * wall-clock time (never ahead of it). A control channel on stdin/stdout (one line per request):
 *   status  -> "status key=value ..." with emulated time and link/stepper observations (ns emulated)
 *   reset   -> resets the MCU (a firmware reset mid-session; cable positions persist) -> "ok reset"
 *   turnaround -> "turnaround ns,ns,..." request delimiter in -> reply delimiter out, emulated [ns]
 *   quit    -> exits
 * The first line written is "pty /dev/pts/N". simavr's own messages go to stderr.
 */
#include <errno.h>
#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "avr_adc.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_elf.h"

#define N_CH 6
#define F_CPU 16000000ULL
#define STEPS_PER_M (3200.0 / (3.14159265358979 * 0.010))
/* tension model: T = max(0, T0 + K x) with x the cable hauled in [m]; FSR divider V = Vcc T / (T + T_HALF) */
#define T0_N 2.0
#define K_N_PER_M 500.0
#define T_HALF_N 10.0
#define VCC_MV 5000

static avr_t *avr;
/* firmware turnaround on the emulated clock: a request's delimiter entering the UART -> the reply's
 * delimiter leaving it (line time of the reply included), last RESP_KEEP values [cycles] */
#define RESP_KEEP 4096
static uint64_t last_rx_delim_cycle, resp[RESP_KEEP], resp_count;
static int awaiting_reply;
static FILE *trace; /* CDPR_SIM_TRACE=path: one line per UART byte, "R|T cycle byte" */
static int pty_master = -1, pty_slave = -1;
static char pty_name[128];
static avr_irq_t *uart_in_irq;
/* host -> firmware bytes waiting for the line (bounded: the kernel pty buffer holds the rest) */
static uint8_t rx_buf[4096];
static size_t rx_head, rx_tail;
static int rx_feeding;
static uint64_t rx_throttled;
static avr_uart_t *uart0;
/* firmware -> host bytes not yet written to the pty */
static uint8_t tx_buf[4096];
static size_t tx_len;
static uint64_t tx_dropped;
static FILE *ctl;

static int dir_level[N_CH], step_level[N_CH];
static long long pos[N_CH];                 /* counted steps, + = hauled in */
static uint64_t rise_cycle[N_CH], dir_change_cycle[N_CH];
static uint64_t pulse_min = UINT64_MAX, dir_setup_min = UINT64_MAX;
static uint64_t last_rx_cycle, last_step_cycle, rx_bytes, steps_total, steps_after_rx, resets;
static int enable_level = 1;
static avr_irq_t *adc_irq[N_CH];

static uint64_t start_wall_ns;

static uint64_t cyc2ns(uint64_t c) { return c * 1000000000ULL / F_CPU; }

static uint32_t tension_mv(int i) {
  double x = pos[i] / STEPS_PER_M;
  double t = T0_N + K_N_PER_M * x;
  if (t < 0) t = 0;
  return (uint32_t)(VCC_MV * t / (t + T_HALF_N) + 0.5);
}

static void feed_adc(int i) { avr_raise_irq(adc_irq[i], tension_mv(i)); }

static void on_step(avr_irq_t *irq, uint32_t value, void *param) {
  int i = (int)(intptr_t)param;
  if (value && !step_level[i]) {
    rise_cycle[i] = avr->cycle;
    pos[i] += dir_level[i] ? 1 : -1;
    last_step_cycle = avr->cycle;
    steps_total++;
    steps_after_rx++;
    if (avr->cycle - dir_change_cycle[i] < dir_setup_min) dir_setup_min = avr->cycle - dir_change_cycle[i];
    feed_adc(i);
  } else if (!value && step_level[i]) {
    if (avr->cycle - rise_cycle[i] < pulse_min) pulse_min = avr->cycle - rise_cycle[i];
  }
  step_level[i] = value ? 1 : 0;
}

static void on_dir(avr_irq_t *irq, uint32_t value, void *param) {
  int i = (int)(intptr_t)param;
  if ((value ? 1 : 0) != dir_level[i]) dir_change_cycle[i] = avr->cycle;
  dir_level[i] = value ? 1 : 0;
}

static void on_enable(avr_irq_t *irq, uint32_t value, void *param) { enable_level = value ? 1 : 0; }

static void on_rx(avr_irq_t *irq, uint32_t value, void *param) {
  if (trace) fprintf(trace, "R %llu %02x\n", (unsigned long long)avr->cycle, value);
  last_rx_cycle = avr->cycle;
  rx_bytes++;
  if (value == 0) {
    last_rx_delim_cycle = avr->cycle;
    awaiting_reply = 1;
  }
  steps_after_rx = 0;
}

#define BYTE_CYCLES (F_CPU * 11 / 1000000) /* start + 8 data + parity slot + stop at 1 Mbaud */

static avr_cycle_count_t feed_rx(avr_t *a, avr_cycle_count_t when, void *param) {
  if (rx_head == rx_tail) {
    rx_feeding = 0;
    return 0;
  }
  /* simavr's receiver releases one byte per 11 bit times (it counts a parity slot) while a 1 Mbaud 8N1
   * line delivers one per 10: hold the line while 2 bytes are unread, or simavr's 64-byte input fifo
   * would overflow on long bursts (bytes lost in the model, not in the firmware) */
  unsigned unread = ((unsigned)uart0->input.write + uart_fifo_fifo_size - uart0->input.read) &
                    (uart_fifo_fifo_size - 1);
  if (unread >= 2) {
    rx_throttled++;
    return when + BYTE_CYCLES / 4;
  }
  avr_raise_irq(uart_in_irq, rx_buf[rx_head]);
  rx_head = (rx_head + 1) % sizeof(rx_buf);
  return when + BYTE_CYCLES;
}

static void flush_tx(void) {
  size_t done = 0;
  while (done < tx_len) {
    ssize_t w = write(pty_master, tx_buf + done, tx_len - done);
    if (w <= 0) break; /* EAGAIN: nobody reading; keep the bytes (bounded) */
    done += (size_t)w;
  }
  memmove(tx_buf, tx_buf + done, tx_len - done);
  tx_len -= done;
}

static uint64_t last_tx_cycle, tx_gap_min = UINT64_MAX, tx_gap_max;

static void on_tx(avr_irq_t *irq, uint32_t value, void *param) {
  if (trace) fprintf(trace, "T %llu %02x\n", (unsigned long long)avr->cycle, value);
  uint64_t gap = avr->cycle - last_tx_cycle;
  last_tx_cycle = avr->cycle;
  if (gap < tx_gap_min) tx_gap_min = gap;
  if (gap > tx_gap_max && gap < F_CPU / 1000) tx_gap_max = gap;
  if (tx_len == sizeof(tx_buf)) {
    tx_dropped++;
    return;
  }
  if (value == 0 && awaiting_reply) {
    resp[resp_count++ % RESP_KEEP] = avr->cycle - last_rx_delim_cycle;
    awaiting_reply = 0;
  }
  tx_buf[tx_len++] = (uint8_t)value;
  if (value == 0 || tx_len >= 64) flush_tx(); /* frame delimiter: send the frame now */
}

static void poll_pty(void) {
  if (tx_len) flush_tx();
  for (;;) {
    size_t next = (rx_tail + 1) % sizeof(rx_buf);
    if (next == rx_head) break;
    size_t room = rx_tail >= rx_head ? sizeof(rx_buf) - rx_tail - (rx_head == 0) : rx_head - rx_tail - 1;
    ssize_t r = read(pty_master, rx_buf + rx_tail, room);
    if (r <= 0) break;
    rx_tail = (rx_tail + (size_t)r) % sizeof(rx_buf);
  }
  if (rx_head != rx_tail && !rx_feeding) {
    rx_feeding = 1;
    avr_cycle_timer_register(avr, BYTE_CYCLES, feed_rx, NULL);
  }
}

static int open_pty(void) {
  if (openpty(&pty_master, &pty_slave, pty_name, NULL, NULL) < 0) return -1;
  struct termios tio;
  tcgetattr(pty_slave, &tio);
  cfmakeraw(&tio);
  tcsetattr(pty_slave, TCSANOW, &tio);
  fcntl(pty_master, F_SETFL, fcntl(pty_master, F_GETFL) | O_NONBLOCK);
  return 0; /* the slave stays open here so the master never sees a hang-up between host sessions */
}

#define CHECK_CYCLES (F_CPU * 50 / 1000000)

/* The CPU sleeps (IDLE) between interrupts: skip the idle cycles at once (simavr's default callback
 * would usleep() them); the main loop paces emulated time against the wall clock. */
static void skip_sleep(avr_t *a, avr_cycle_count_t how_long) {}

static uint64_t wall_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (uint64_t)ts.tv_sec * 1000000000ULL + (uint64_t)ts.tv_nsec;
}

static void report_status(void) {
  fprintf(ctl, "status t_ns=%llu wall_ns=%llu rx_bytes=%llu last_rx_ns=%llu last_step_ns=%llu steps_total=%llu "
          "steps_after_rx=%llu pulse_min_ns=%llu dir_setup_min_ns=%llu enable=%d resets=%llu rx_throttled=%llu tx_dropped=%llu tx_gap_min_ns=%llu tx_gap_max_ns=%llu last_tx_ns=%llu pos=",
          (unsigned long long)cyc2ns(avr->cycle), (unsigned long long)(wall_ns() - start_wall_ns),
          (unsigned long long)rx_bytes,
          (unsigned long long)cyc2ns(last_rx_cycle), (unsigned long long)cyc2ns(last_step_cycle),
          (unsigned long long)steps_total, (unsigned long long)steps_after_rx,
          (unsigned long long)(pulse_min == UINT64_MAX ? 0 : cyc2ns(pulse_min)),
          (unsigned long long)(dir_setup_min == UINT64_MAX ? 0 : cyc2ns(dir_setup_min)), enable_level,
          (unsigned long long)resets, (unsigned long long)rx_throttled, (unsigned long long)tx_dropped,
          (unsigned long long)cyc2ns(tx_gap_min == UINT64_MAX ? 0 : tx_gap_min), (unsigned long long)cyc2ns(tx_gap_max),
          (unsigned long long)cyc2ns(last_tx_cycle));
  for (int i = 0; i < N_CH; i++) fprintf(ctl, "%s%lld", i ? "," : "", pos[i]);
  fprintf(ctl, " adc_mv=");
  for (int i = 0; i < N_CH; i++) fprintf(ctl, "%s%u", i ? "," : "", tension_mv(i));
  fprintf(ctl, "\n");
  fflush(ctl);
}

/* Handle complete request lines on stdin; returns 0 to quit. */
static int poll_control(void) {
  static char line[256];
  static size_t len;
  struct pollfd pfd = {0, POLLIN, 0};
  while (poll(&pfd, 1, 0) > 0) {
    if (!(pfd.revents & POLLIN)) return 0; /* hang-up */
    char c;
    ssize_t r = read(0, &c, 1);
    if (r <= 0) return 0;
    if (c != '\n') {
      if (len < sizeof(line) - 1) line[len++] = c;
      continue;
    }
    line[len] = 0;
    len = 0;
    if (!strcmp(line, "status")) {
      report_status();
    } else if (!strcmp(line, "reset")) {
      avr_reset(avr);
      resets++;
      for (int i = 0; i < N_CH; i++) feed_adc(i);
      fprintf(ctl, "ok reset\n");
      fflush(ctl);
    } else if (!strcmp(line, "turnaround")) { /* the kept turnaround times [ns], oldest first */
      uint64_t n = resp_count < RESP_KEEP ? resp_count : RESP_KEEP;
      fprintf(ctl, "turnaround");
      for (uint64_t k = resp_count - n; k < resp_count; k++)
        fprintf(ctl, "%s%llu", k == resp_count - n ? " " : ",", (unsigned long long)cyc2ns(resp[k % RESP_KEEP]));
      fprintf(ctl, "\n");
      fflush(ctl);
    } else if (!strcmp(line, "quit")) {
      return 0;
    } else {
      fprintf(ctl, "error unknown request '%s'\n", line);
      fflush(ctl);
    }
  }
  return 1;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s FIRMWARE.elf\n", argv[0]);
    return 2;
  }
  ctl = fdopen(dup(1), "w");
  if (getenv("CDPR_SIM_TRACE")) trace = fopen(getenv("CDPR_SIM_TRACE"), "w");
  dup2(2, 1); /* simavr prints on stdout: send it to stderr, keep stdout for the control channel */

  elf_firmware_t fw;
  memset(&fw, 0, sizeof(fw));
  if (elf_read_firmware(argv[1], &fw) != 0) {
    fprintf(stderr, "cdpr_sim: cannot read firmware %s\n", argv[1]);
    return 2;
  }
  avr = avr_make_mcu_by_name("atmega2560");
  if (!avr) {
    fprintf(stderr, "cdpr_sim: simavr has no atmega2560\n");
    return 2;
  }
  avr_init(avr);
  avr->frequency = F_CPU;
  avr->vcc = avr->avcc = avr->aref = VCC_MV;
  avr_load_firmware(avr, &fw);
  avr->frequency = F_CPU;

  if (open_pty() < 0) {
    fprintf(stderr, "cdpr_sim: cannot open a pseudo-terminal: %s\n", strerror(errno));
    return 2;
  }
  uint32_t uart_flags = 0; /* binary link: no stdio echo; no usleep() when the firmware polls UCSRA */
  avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &uart_flags);
  uart_flags &= ~(AVR_UART_FLAG_POOL_SLEEP | AVR_UART_FLAG_STDIO);
  avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &uart_flags);
  uart_in_irq = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
  avr_irq_register_notify(uart_in_irq, on_rx, NULL);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_tx, NULL);
  for (avr_io_t *io = avr->io_port; io; io = io->next)
    if (!strcmp(io->kind, "uart") && ((avr_uart_t *)io)->name == '0') uart0 = (avr_uart_t *)io;
  if (!uart0) {
    fprintf(stderr, "cdpr_sim: no UART0 in simavr's atmega2560\n");
    return 2;
  }
  for (int i = 0; i < N_CH; i++) {
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('A'), IOPORT_IRQ_PIN0 + i), on_step,
                            (void *)(intptr_t)i);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('C'), IOPORT_IRQ_PIN0 + i), on_dir,
                            (void *)(intptr_t)i);
    adc_irq[i] = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + i);
    feed_adc(i);
  }
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('L'), IOPORT_IRQ_PIN0), on_enable, NULL);

  fprintf(ctl, "pty %s\n", pty_name);
  fflush(ctl);

  avr->sleep = skip_sleep;
  uint64_t start = start_wall_ns = wall_ns();
  uint64_t next_check = 0, next_control = 0;
  for (;;) {
    int state = avr_run(avr);
    if (state == cpu_Done || state == cpu_Crashed) {
      fprintf(stderr, "cdpr_sim: firmware stopped (state %d)\n", state);
      break;
    }
    if (avr->cycle >= next_check) { /* every 50 us of emulated time */
      next_check = avr->cycle + CHECK_CYCLES;
      /* pace: emulated time never runs ahead of wall-clock time */
      int64_t ahead = (int64_t)cyc2ns(avr->cycle) - (int64_t)(wall_ns() - start);
      if (ahead > 50000) {
        struct timespec ts = {0, ahead > 999999999 ? 999999999 : ahead};
        nanosleep(&ts, NULL);
      }
      poll_pty();
      if (avr->cycle >= next_control) { /* control requests are rare: every 1 ms of emulated time */
        next_control = avr->cycle + F_CPU / 1000;
        if (!poll_control()) break;
      }
    }
  }
  close(pty_master);
  close(pty_slave);
  if (trace) fclose(trace);
  return 0;
}
