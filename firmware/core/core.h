/* core.h: the portable firmware core (C99, gcc and SDCC): modules, their state and entry points.
 *
 * Time: every counter named *_ms counts 1 ms control ticks. Speeds: encoder pulses per tick
 * (2048 per revolution), or Q8 pulses per tick (x 256) where the name says q8. Duty: 1/1000 of full
 * scale ("permille"), -1000..1000. */
#ifndef MCG_FIRMWARE_CORE_CORE_H
#define MCG_FIRMWARE_CORE_CORE_H

#include <stdint.h> /* int16_t, int32_t, uint8_t */

#include "compiler.h"     /* MCG_XDATA */
#include "mcg_protocol.h" /* MCG_* */

#ifdef __cplusplus
extern "C" {
#endif

/* app.c: the service loop ------------------------------------------------------------------------ */
/* Power-on state: registers at their defaults, outputs off, parser empty. */
void core_init(void);
/* One pass of the main loop: runs the control update for elapsed ticks, then the receive parser,
 * the log dump and the service tasks (keypad, LCD). Never blocks. */
void core_poll(void);
/* Frame dispatch (called by the parser with a CRC-checked frame). */
void app_dispatch(uint8_t cmd, const uint8_t MCG_XDATA* payload, uint8_t len);

/* frame.c: framing, CRC, resynchronising parser ----------------------------------------------- */
void frame_init(void);
/* Feeds one received byte; complete frames go to app_dispatch, bad ones to an MCG_MSG_ERROR. */
void frame_rx_byte(uint8_t byte);
/* Advances the inter-byte timer by one tick; drops a partial frame after MCG_FRAME_TIMEOUT_MS. */
void frame_rx_tick(void);
/* Drops the partial frame after lost bytes and reports MCG_ST_OVERRUN. */
void frame_rx_overrun(void);
/* Sends a whole frame, or none (counting g_tx_drops) if the transmit buffer lacks room.
 * Returns 1 if queued. */
uint8_t frame_send(uint8_t cmd, const uint8_t MCG_XDATA* payload, uint8_t len) MCG_REENTRANT;
/* Sends an answer: CMD | MCG_REPLY_BIT, the status, then len bytes of data. */
uint8_t frame_reply(uint8_t cmd, uint8_t status, const uint8_t MCG_XDATA* data, uint8_t len) MCG_REENTRANT;
extern uint16_t MCG_XDATA g_rx_errors; /* frames dropped by the parser */
extern uint16_t MCG_XDATA g_tx_drops;  /* frames not sent for lack of room */

/* regs.c: the register map ------------------------------------------------------------------- */
/* MCG_ST_OK and the value in *value, or MCG_ST_BAD_REG. */
uint8_t regs_read(uint8_t reg, int16_t* value) MCG_REENTRANT;
/* Who writes a register. The shadow set belongs to the writer that staged into it first until a
 * commit or discard: another writer's staged write or commit is refused with MCG_ST_BUSY, so no
 * writer commits a set another left half-written. Only the link may drop another's set (commit 0),
 * and not a playing sequence's (it would commit the rest of its set alone). */
#define MCG_WRITER_LINK 1u
#define MCG_WRITER_SEQ 2u
#define MCG_WRITER_KEYPAD 3u
/* Range-checked write with its side effects (log interval, outputs, commit, ...) by `writer`; an
 * MCG_RS register is written into the shadow set. MCG_ST_OK or the reason it was refused, the
 * register then unchanged. */
uint8_t regs_write_by(uint8_t writer, uint8_t reg, int16_t value);
/* regs_write_by(MCG_WRITER_LINK, ...): the link's write, and the power-on defaults. */
uint8_t regs_write(uint8_t reg, int16_t value);
/* As regs_read, but an MCG_RS register shows its shadow value (what a write left there). */
uint8_t regs_read_staged(uint8_t reg, int16_t* value);
/* A write as one atomic change, as the keypad makes it: an MCG_RS register is written into a fresh
 * copy of the active set and committed; any other is written. MCG_ST_OK or the refusal (MCG_ST_BUSY
 * while another writer has a set staged). */
uint8_t regs_apply(uint8_t reg, int16_t value);
/* The static range of register reg (which must exist). */
int16_t regs_min(uint8_t reg);
int16_t regs_max(uint8_t reg);
/* 1 if the register exists and is writable. */
uint8_t regs_writable(uint8_t reg);
/* 1 if a write of reg stages into, commits or discards the controller's shadow set. */
uint8_t regs_staging(uint8_t reg);
void regs_init(void);
extern uint8_t g_mode;                 /* MCG_MODE_* */
extern int16_t MCG_XDATA g_rpm_cmd;    /* rpm */
extern int16_t g_duty_set;             /* open-loop duty, 1/1000 */
extern int16_t MCG_XDATA g_duty_step;  /* keypad step, 1/1000 */
extern uint8_t MCG_XDATA g_service_ms; /* keypad/duty service period */
extern uint8_t MCG_XDATA g_stream_on;
extern uint8_t MCG_XDATA g_clutch_on;
extern uint8_t MCG_XDATA g_load_on;

/* control.c: speed measurement and the 1 ms controller --------------------------------------- */
void control_init(void);
/* The 1 ms update: pulses counted in this tick -> controller -> PWM write (control_tick.c, or its
 * assembly twin on the 8051). */
void control_tick(uint8_t pulses);
/* The speed window: pulses counted in this tick (after control_tick, off the critical path). */
void speed_tick(uint8_t pulses);
/* One step of the command history after a command change (called by control_tick while
 * g_ctl_settle > 0). */
void control_settle(void);
/* Controller state shared by control.c and the tick (also the 8051 assembly: keep in data memory). */
extern uint8_t g_ctl_p_hi;               /* pulse limit keeping e >= -8191 */
extern int32_t MCG_IDATA g_ctl_r[3];     /* R for the next three ticks */
extern uint8_t g_ctl_r_k;                /* which of them is next (2 = settled) */
extern int32_t g_ctl_u;                  /* U, Q(F+8) duty */
extern int32_t g_ctl_u_min, g_ctl_u_max; /* limits of U */
extern uint8_t g_ctl_shift;              /* F + 8 */
extern uint8_t g_ctl_settle;             /* ticks until the command history is settled */
/* The controller's set: what the MCG_RS registers hold. The active set (g_mode, g_kp, ..., below) is
 * what the update runs; writes go to the shadow set, which the update never reads. */
typedef struct {
  int16_t kp, b0, b1, b2; /* Q(F) */
  int16_t duty_bias, duty_min, duty_max;
  uint8_t mode, coef_frac;
} CtlSet;
extern CtlSet MCG_XDATA g_ctl_shadow;
/* Makes the shadow set active at once (between two updates), bumpless: PI and PID continue from the
 * present duty, open loop keeps it. MCG_ST_OK; or MCG_ST_NO_GAINS (a closed-loop mode whose gains are
 * all zero), MCG_ST_LIMITS (duty_min above duty_max), the active set then unchanged. Either way the
 * shadow set equals the active one afterwards. */
uint8_t control_commit(void);
/* The shadow set becomes a copy of the active one. */
void control_discard(void);
/* After a write into the shadow set by `writer` (MCG_WRITER_*): recomputes what it derives (limits,
 * bias, R in its format), so that a commit only copies; the first such write makes writer its owner. */
void control_staged(uint8_t writer);
/* The writer that owns the shadow set (it staged since the last commit or discard), or 0. */
uint8_t control_owner(void);
/* 1 if the shadow set differs from the active one. */
uint8_t control_pending(void);
void control_set_rpm_cmd(int16_t rpm);
/* The same for a command already in Q8 pulses per tick (control_rpm_to_q8): a level precomputed. */
void control_set_q8(int16_t r_q8);
/* Precomputes R for commands that alternate between q_a and q_b (Q8), from the present command on,
 * with the active set, so that control_set_q8 of either costs copies, not products (exactly the same
 * R), until the next commit; not while a set is staged. */
void control_levels(int16_t q_a, int16_t q_b) MCG_REENTRANT;
/* Recomputes what depends on the command, the coefficients or the mode (after a change of any). */
void control_refresh(void);
/* Speed over the last MCG_SPEED_WINDOW_MS: rpm = counts * 1875 / 1024, rounded. */
int16_t control_rpm(void);
/* rpm -> Q8 pulses per tick: r = rpm * 2048 * 256 / 60000, rounded. */
int16_t control_rpm_to_q8(int16_t rpm);
extern int16_t MCG_XDATA g_kp, g_b0, g_b1, g_b2; /* Q(F) coefficients, 1/1000 duty per pulse/ms */
extern uint8_t MCG_XDATA g_coef_frac;            /* F */
extern int16_t MCG_XDATA g_duty_min, g_duty_max, g_duty_bias;
extern int16_t g_duty_out;               /* the duty written to the PWM by the last update */
extern uint8_t g_saturated;              /* last update hit duty_min or duty_max */
extern uint16_t MCG_XDATA g_counts_16ms; /* pulses in the last 16 ticks */

/* logger.c: the RAM log (255 points at MCG_LOG_XADDR) ----------------------------------------- */
void logger_init(void);
void logger_tick(uint8_t pulses);
/* MCG_ST_OK, or MCG_ST_BUSY while a dump is being sent. Restarts from point 0. */
uint8_t logger_start(void);
uint8_t logger_set_interval(uint8_t interval_ms); /* MCG_ST_BUSY while recording */
extern uint16_t MCG_XDATA MCG_AT(MCG_LOG_XADDR) g_log[MCG_LOG_POINTS];
extern uint8_t MCG_XDATA g_log_count;    /* points recorded */
extern uint8_t MCG_XDATA g_log_interval; /* ms between points */
extern uint8_t MCG_XDATA g_log_running;
/* Starts a dump: app.c's service loop sends the log as MCG_MSG_LOG_DATA frames, chunk g_dump_next
 * onwards. MCG_ST_BUSY while recording. The logger owns both states, so that recording and dumping
 * exclude each other without the logger calling up into app.c. */
uint8_t logger_dump_start(void);
extern uint8_t MCG_XDATA g_dump_next; /* next chunk index, MCG_LOG_DUMP_FRAMES when idle */

/* seq.c: command sequence playback (the report's Simulink mode) ------------------------------- */
void seq_init(void);
void seq_tick(void);
/* Stores n entries (5 bytes each) at index; MCG_ST_OK, BUSY, RANGE, BAD_REG or READ_ONLY. */
uint8_t seq_write(uint8_t index, const uint8_t MCG_XDATA* entries, uint8_t n);
uint8_t seq_clear(void);
/* Play, loop or stop. A sequence with entries that stage (regs_staging) owns the shadow set from
 * its start to its stop: it starts only when no other writer has a set staged (else MCG_ST_BUSY),
 * and a set it leaves staged at its stop is discarded. */
uint8_t seq_set_state(uint8_t state);
/* 1 while a playing sequence owns the shadow set. */
extern uint8_t MCG_XDATA g_seq_owns_set;
extern uint8_t MCG_XDATA g_seq_len;
extern uint8_t MCG_XDATA g_seq_state;

/* excite.c: identification inputs played by the board (PRBS, staircase, chirp) ----------------- */
void excite_init(void);
/* Before the control update of every tick: the next level of a running excitation. */
void excite_tick(void);
/* 1 starts (MCG_ST_RANGE if no kind is set or a level is out of the target's range), 0 stops and
 * returns the target to exc_offset. */
uint8_t excite_set_run(uint8_t run);
/* Stores one setting (exc_kind .. exc_periods, exc_f0 .. exc_sweep, range-checked by regs_write). */
void excite_set(uint8_t reg, int16_t v) MCG_REENTRANT;
extern uint8_t MCG_XDATA g_exc_kind, g_exc_order, g_exc_steps, g_exc_periods, g_exc_run;
extern uint16_t MCG_XDATA g_exc_div;
extern int16_t MCG_XDATA g_exc_amp, g_exc_offset;
extern uint16_t MCG_XDATA g_exc_f0, g_exc_f1, g_exc_sweep;

/* menu.c: keypad and LCD --------------------------------------------------------------------- */
void menu_init(void);
/* Service task, every g_service_ms: samples the keypad and acts on keys. */
void menu_service(void);
/* Rewrites both LCD lines (every 500 ms, and after keys). */
void menu_refresh(void);
#define MENU_LCD_REFRESH_MS 500u
extern char MCG_XDATA g_lcd[2][17]; /* last text sent to the LCD, NUL-terminated */

/* app.c: streaming and the log dump ---------------------------------------------------------- */
extern uint8_t MCG_XDATA g_stream_seq;
/* 1 if the last non-zero drive was negative: the sign given to the direction-less encoder pulses
 * by the stream and the RAM log (updated at the start of each tick, for the tick that ended). */
extern uint8_t MCG_XDATA g_count_neg;
/* 1 if the tick now running opens a stream sample (or the stream is off): a sequence starts on such
 * a tick, so that its entries fall on sample boundaries when their delays are multiples of
 * MCG_STREAM_PERIOD_MS. */
uint8_t app_stream_sample_opens(void);

#ifdef __cplusplus
}
#endif

#endif
