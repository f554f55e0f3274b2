/* mcg_protocol.h: the wire contract between the SAB 80C515 board and the host (see mcg-protocol(7)).
 *
 * One header for both sides: the firmware (SDCC, C99) and the host tools (C++20) include it, so every
 * constant below is defined exactly once. It holds macros, the register table (MCG_REGISTERS), byte
 * structs of the payloads and a conversion-clean inline CRC, so it compiles warning-free as C99 and
 * as C++ (-Wold-style-cast, -Wconversion).
 *
 * Frame (both directions), all multi-byte fields little-endian:
 *
 *   SYNC  LEN  CMD  PAYLOAD[LEN]  CRC_LO  CRC_HI
 *   0xA5  0..MCG_MAX_PAYLOAD
 *
 * CRC = CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor) over LEN, CMD and
 * PAYLOAD. A request CMD has bit 7 clear; its answer has CMD | 0x80 and PAYLOAD[0] = a status code,
 * followed by the answer's data when the status is MCG_ST_OK. Frames the board sends on its own
 * (stream blocks, log dump, frame errors) use CMD 0xF0..0xFF.
 */
#ifndef MCG_FIRMWARE_INCLUDE_MCG_PROTOCOL_H
#define MCG_FIRMWARE_INCLUDE_MCG_PROTOCOL_H

/* Protocol revision: bumped on any incompatible change of this header. */
#define MCG_PROTOCOL_VERSION 5u

/* Firmware version reported by MCG_CMD_VERSION. */
#include <stdint.h> /* uint8_t */

#define MCG_FW_VERSION_MAJOR 0u
#define MCG_FW_VERSION_MINOR 5u
#define MCG_FW_VERSION_PATCH 0u

/* Board ids reported by MCG_CMD_VERSION. */
#define MCG_BOARD_C515 0u  /* the EMAC SAB 80C515 board */
#define MCG_BOARD_UCSIM 1u /* the SIM image in s51's 80C517 model */
#define MCG_BOARD_HOST 2u  /* the host layer (unit tests, mcg-sim --board) */

/* ---- Framing ---------------------------------------------------------------------------------- */
#define MCG_SYNC 0xA5u
#define MCG_MAX_PAYLOAD 64u      /* LEN above this is a framing error: the parser resynchronises */
#define MCG_FRAME_OVERHEAD 5u    /* SYNC, LEN, CMD, CRC_LO, CRC_HI */
#define MCG_FRAME_TIMEOUT_MS 20u /* a gap longer than this inside a frame drops the partial frame */
#define MCG_CRC_INIT 0xFFFFu
#define MCG_REPLY_BIT 0x80u

/* ---- Requests (host -> board); the answer is CMD | MCG_REPLY_BIT ------------------------------ */
#define MCG_CMD_VERSION 0x01u   /* ()                       -> st, proto, major, minor, patch, board */
#define MCG_CMD_READ 0x02u      /* (reg u8)                 -> st, reg u8, value i16 */
#define MCG_CMD_WRITE 0x03u     /* (reg u8, value i16)      -> st, reg u8, value i16 (as now held) */
#define MCG_CMD_LOG_START 0x04u /* ()                       -> st; records MCG_LOG_POINTS points */
/* MCG_CMD_LOG_DUMP is followed by MCG_LOG_DUMP_FRAMES frames MCG_MSG_LOG_DATA */
#define MCG_CMD_LOG_DUMP 0x05u  /* ()                       -> st, points u8, interval_ms u8 */
#define MCG_CMD_SEQ_WRITE 0x06u /* (index u8, n x entry)    -> st, next index u8 */
#define MCG_CMD_SEQ_CLEAR 0x07u /* ()                       -> st */
/* Registers first..first+count-1 in one answer (reads as MCG_CMD_READ), count 1..MCG_READ_MANY_MAX:
 * a full read-back costs one answer of the line's spare room beside the stream, not one per register. */
#define MCG_CMD_READ_MANY 0x08u /* (first u8, count u8)     -> st, first u8, count u8, count x i16 */
/* Registers in the order listed, count = LEN 1..MCG_READ_MANY_MAX (reads as MCG_CMD_READ): the
 * registers the board changes itself are scattered among the configuration ones, and a port owner
 * that holds the configuration asks for the rest in one answer. The answer's header is
 * McgReadManyRequest with first = the first id listed. */
#define MCG_CMD_READ_LIST 0x09u /* (count x reg u8)         -> st, first u8, count u8, count x i16 */

/* ---- Payloads as byte structs ------------------------------------------------------------------
 * Every member is a uint8_t (multi-byte fields as [lo, hi]), so no compiler pads them and sizeof
 * is the length on the wire: both sides check and build payloads with sizeof, never a number. An
 * answer's payload is the status byte, then (when MCG_ST_OK) the answer struct. */
typedef struct {
  uint8_t reg;
} McgReadRequest;
typedef struct {
  uint8_t reg;
  uint8_t value[2];
} McgWriteRequest;
typedef struct {
  uint8_t reg;
  uint8_t value[2];
} McgRegisterAnswer; /* MCG_CMD_READ and MCG_CMD_WRITE: the register and the value it holds */
typedef struct {
  uint8_t first;
  uint8_t count;
} McgReadManyRequest; /* also the header of the answer, before count x i16 */
typedef struct {
  uint8_t protocol;
  uint8_t major;
  uint8_t minor;
  uint8_t patch;
  uint8_t board;
} McgVersionAnswer;
typedef struct {
  uint8_t points;
  uint8_t interval_ms;
} McgDumpAnswer;
typedef struct {
  uint8_t next_index;
} McgSeqWriteAnswer;
typedef struct {
  uint8_t first; /* index of the first point */
  uint8_t n;     /* points that follow, u16 each */
} McgLogDataHeader;
typedef struct {
  uint8_t seq;
  uint8_t rpm_cmd[2]; /* i16, at the block's last sample (protocol 2, see "Stream blocks") */
} McgStreamHeader;
typedef struct {
  uint8_t delay_ms[2]; /* u16, after the previous entry */
  uint8_t reg;
  uint8_t value[2]; /* i16 */
} McgSeqEntry;

/* Registers in one MCG_CMD_READ_MANY or MCG_CMD_READ_LIST answer: status, header and values fill
 * MCG_MAX_PAYLOAD. */
#define MCG_READ_MANY_MAX ((MCG_MAX_PAYLOAD - 1u - sizeof(McgReadManyRequest)) / 2u)

/* ---- Frames the board sends on its own -------------------------------------------------------- */
#define MCG_MSG_STREAM 0xF0u   /* stream block, see MCG_STREAM_* */
#define MCG_MSG_LOG_DATA 0xF1u /* RAM log dump, see MCG_LOGDATA_* */
#define MCG_MSG_ERROR 0xFFu    /* (status u8): a frame was dropped before its CMD could be trusted */

/* ---- Status codes (first payload byte of every answer, and of MCG_MSG_ERROR) ------------------ */
#define MCG_ST_OK 0u
#define MCG_ST_BAD_CRC 1u    /* CRC mismatch (MCG_MSG_ERROR) */
#define MCG_ST_TOO_LONG 2u   /* LEN > MCG_MAX_PAYLOAD (MCG_MSG_ERROR) */
#define MCG_ST_TIMEOUT 3u    /* frame truncated: gap > MCG_FRAME_TIMEOUT_MS (MCG_MSG_ERROR) */
#define MCG_ST_OVERRUN 4u    /* receive buffer overflowed, bytes were lost (MCG_MSG_ERROR) */
#define MCG_ST_BAD_CMD 5u    /* unknown command */
#define MCG_ST_BAD_LENGTH 6u /* payload length wrong for the command */
#define MCG_ST_BAD_REG 7u    /* unknown register */
#define MCG_ST_READ_ONLY 8u  /* register cannot be written */
#define MCG_ST_RANGE 9u      /* value outside the register's range; register unchanged */
#define MCG_ST_BUSY                                                                                          \
  10u                        /* not now: log busy, sequence playing, an excitation setting while it runs, or \
                                the controller's set staged by another writer */
#define MCG_ST_OWNED 11u     /* duty written in a closed-loop mode: the controller owns it */
#define MCG_ST_NO_GAINS 12u  /* commit of a closed-loop mode whose every gain is zero; nothing changed */
#define MCG_ST_LIMITS 13u    /* commit of duty_min above duty_max; nothing changed */
#define MCG_ST_COUNT 14u

/* ---- Units and fixed-point formats ------------------------------------------------------------ */
#define MCG_TICK_US 1000u            /* control sample period: 1 ms */
#define MCG_COUNTS_PER_REV 2048u     /* encoder counts per motor revolution */
#define MCG_DUTY_FULL 1000           /* duty unit: 1/1000 of full scale (0.1 %); PWM has 1000 steps */
#define MCG_ERR_FRAC_BITS 8u         /* controller error e: Q8 encoder counts per 1 ms */
#define MCG_ERR_LIMIT 8191           /* e >= -this: pulses limited to (r + 8191) / 256 (937 rpm) */
#define MCG_COEF_FRAC_BITS_MAX 12u   /* coefficient fractional bits F (register MCG_REG_COEF_FRAC) */
#define MCG_SPEED_WINDOW_MS 16u      /* speed counting window: rpm = counts_16ms * 1875 / 1024 */
#define MCG_RPM_PER_WINDOW_NUM 1875u /* 60000 / (2048 * 16) = 1875 / 1024 rpm per count */
#define MCG_RPM_PER_WINDOW_DEN 1024u

/* ---- Registers ------------------------------------------------------------------------------
 * Every register travels as i16 little-endian. Its id is MCG_REG_<NAME>; everything else about it
 * is its row in MCG_REGISTERS below, the one table that the firmware (core/regs.c: access, range,
 * power-on value), the host (src/lib/link/registers.cpp: names, units, range checks before
 * sending) and the register table of mcg-protocol(7) (checked by tests/firmware/test_fw_regs.cpp)
 * are expanded from. */
#define MCG_REG_MODE 0x01u
#define MCG_REG_RPM_CMD 0x02u
#define MCG_REG_DUTY 0x03u
#define MCG_REG_DUTY_STEP 0x04u
#define MCG_REG_DUTY_BIAS 0x05u
#define MCG_REG_KP 0x06u
#define MCG_REG_B0 0x07u
#define MCG_REG_B1 0x08u
#define MCG_REG_B2 0x09u
#define MCG_REG_COEF_FRAC 0x0Au
#define MCG_REG_DUTY_MIN 0x0Bu
#define MCG_REG_DUTY_MAX 0x0Cu
#define MCG_REG_SERVICE_MS 0x0Du
#define MCG_REG_LOG_INTERVAL 0x0Eu
#define MCG_REG_LOG_COUNT 0x0Fu
#define MCG_REG_STREAM 0x10u
#define MCG_REG_CLUTCH 0x11u
#define MCG_REG_LOAD 0x12u
#define MCG_REG_RPM 0x13u
#define MCG_REG_COUNTS_16MS 0x14u
#define MCG_REG_SEQ_LEN 0x15u
#define MCG_REG_SEQ_STATE 0x16u
#define MCG_REG_FLAGS 0x17u
#define MCG_REG_RX_ERRORS 0x18u
#define MCG_REG_TX_DROPS 0x19u
#define MCG_REG_STREAM_SEQ 0x1Au
#define MCG_REG_COMMIT 0x1Bu
#define MCG_REG_EXC_KIND 0x1Cu
#define MCG_REG_EXC_ORDER 0x1Du
#define MCG_REG_EXC_STEPS 0x1Eu
#define MCG_REG_EXC_DIV 0x1Fu
#define MCG_REG_EXC_AMP 0x20u
#define MCG_REG_EXC_OFFSET 0x21u
#define MCG_REG_EXC_PERIODS 0x22u
#define MCG_REG_EXC_RUN 0x23u
#define MCG_REG_EXC_F0 0x24u
#define MCG_REG_EXC_F1 0x25u
#define MCG_REG_EXC_SWEEP 0x26u
#define MCG_REG_COUNT 0x27u /* ids 0x01..MCG_REG_COUNT-1 exist, in the order of MCG_REGISTERS */

/* Access column. */
#define MCG_RO 0u /* read only: a write is refused with MCG_ST_READ_ONLY */
#define MCG_RW 1u /* every write is range-checked, from the link, the keypad and playback alike */
/* Staged (range-checked as MCG_RW): the controller's set (mode, gains, format, bias, limits). A write
 * goes to the shadow set, which the running loop never reads; writing 1 to MCG_REG_COMMIT checks the
 * whole set and makes it active between two ticks, bumpless. Reads show the active set. */
#define MCG_RS 2u

/* Unit column: what the raw i16 counts (the host shows duty in %, gains as raw / 2^F). */
#define MCG_UNIT_MODE 0u     /* MCG_MODE_* */
#define MCG_UNIT_SEQ 1u      /* MCG_SEQ_* */
#define MCG_UNIT_RPM 2u      /* rev/min */
#define MCG_UNIT_PERMILLE 3u /* 1/1000 of full-scale duty */
#define MCG_UNIT_GAIN 4u     /* Q(F): 1/1000 duty per pulse/ms, times 2^F, F = coef_frac */
#define MCG_UNIT_BITS 5u     /* bits */
#define MCG_UNIT_MS 6u       /* milliseconds */
#define MCG_UNIT_COUNT 7u    /* a count (counters read as u16) */
#define MCG_UNIT_SWITCH 8u   /* 0 off, 1 on */
#define MCG_UNIT_FLAGS 9u    /* MCG_FLAG_* bits */
#define MCG_UNIT_CLUTCH 10u  /* MCG_CLUTCH_*: the clutch states of mcg-csv(5) the board can take */
#define MCG_UNIT_EXC 11u     /* MCG_EXC_* */
#define MCG_UNIT_LEVEL 12u   /* the excitation's target: 1/1000 duty in mode open, rpm in p, pi, pid */
#define MCG_UNIT_CHZ 13u     /* 1/100 Hz */
#define MCG_UNIT_S 14u       /* seconds */

#define MCG_I16_MIN (-32767 - 1)
#define MCG_I16_MAX 32767

/* Capture column: what a capture's board_config metadata states (mcg-csv(5)): the controller's
 * set and mode, the registers whose value each row also carries, nothing else. */
#define MCG_CAP_NO 0u    /* not stated */
#define MCG_CAP_STATE 1u /* stated, and set on the emulated core when a capture is replayed */
#define MCG_CAP_ROW 2u   /* stated; each row carries its value (rpm_cmd, clutch, r_load columns) */

/* Keypad column: MCG_KEY(position in the keypad's menu, 1.., contiguous; LCD label, 16 characters
 * at most) or MCG_NO_KEY. MCG_KEY_POS and MCG_KEY_LABEL take the column apart. */
#define MCG_KEY(pos, label) (pos, label)
#define MCG_NO_KEY (0u, "")
#define MCG_KEY_POS_(pos, label) pos
#define MCG_KEY_LABEL_(pos, label) label
#define MCG_KEY_POS(keypad) MCG_KEY_POS_ keypad
#define MCG_KEY_LABEL(keypad) MCG_KEY_LABEL_ keypad

/* X(NAME, name, access, min, max, power-on value, unit, capture, keypad, doc), one row per register
 * in id order. min..max is the static range a write must meet (for MCG_RO: the range a read can
 * show); the firmware checks the dynamic parts the doc names (duty within duty_min..duty_max,
 * duty_min <= duty_max). Plain C89 tokens: SDCC expands it into code-memory tables. */ /* clang-format off */
#define MCG_REGISTERS(X) \
  X(MODE, "mode", MCG_RS, 0, MCG_MODE_COUNT - 1, MCG_MODE_OPEN, MCG_UNIT_MODE, \
    MCG_CAP_STATE, MCG_KEY(1, "Mode 0OL 1P 2PI"), "controller: open, p, pi, pid") \
  X(RPM_CMD, "rpm_cmd", MCG_RW, 120, 720, 420, MCG_UNIT_RPM, \
    MCG_CAP_ROW, MCG_KEY(2, "Speed cmd rpm"), "speed command, rpm") \
  X(DUTY, "duty", MCG_RW, -MCG_DUTY_FULL, MCG_DUTY_FULL, 0, MCG_UNIT_PERMILLE, \
    MCG_CAP_NO, MCG_NO_KEY, \
    "motor duty, % (read: the output; write: open loop only, within duty_min..duty_max)") \
  X(DUTY_STEP, "duty_step", MCG_RW, 1, MCG_DUTY_FULL, 10, MCG_UNIT_PERMILLE, \
    MCG_CAP_NO, MCG_KEY(11, "Duty step 0.1%"), "keypad up/down duty step, %") \
  X(DUTY_BIAS, "duty_bias", MCG_RS, -MCG_DUTY_FULL, MCG_DUTY_FULL, 0, MCG_UNIT_PERMILLE, \
    MCG_CAP_STATE, MCG_KEY(8, "P bias 0.1%"), "P mode: u = bias + kp e, %") \
  X(KP, "kp", MCG_RS, MCG_I16_MIN, MCG_I16_MAX, 0, MCG_UNIT_GAIN, \
    MCG_CAP_STATE, MCG_KEY(3, "Kp"), "P gain, 1/1000 duty per pulse/ms") \
  X(B0, "b0", MCG_RS, MCG_I16_MIN, MCG_I16_MAX, 0, MCG_UNIT_GAIN, \
    MCG_CAP_STATE, MCG_KEY(4, "PI/PID b0"), \
    "PI/PID: u[n] = u[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2], 1/1000 duty per pulse/ms") \
  X(B1, "b1", MCG_RS, MCG_I16_MIN, MCG_I16_MAX, 0, MCG_UNIT_GAIN, \
    MCG_CAP_STATE, MCG_KEY(5, "PI/PID b1"), "PI/PID coefficient of e[n-1]") \
  X(B2, "b2", MCG_RS, MCG_I16_MIN, MCG_I16_MAX, 0, MCG_UNIT_GAIN, \
    MCG_CAP_STATE, MCG_KEY(6, "PID b2"), "PID coefficient of e[n-2]") \
  X(COEF_FRAC, "coef_frac", MCG_RS, 0, MCG_COEF_FRAC_BITS_MAX, 8, MCG_UNIT_BITS, \
    MCG_CAP_STATE, MCG_KEY(7, "Gain frac bits"), "fractional bits F of kp, b0, b1, b2") \
  X(DUTY_MIN, "duty_min", MCG_RS, -MCG_DUTY_FULL, MCG_DUTY_FULL, 0, MCG_UNIT_PERMILLE, \
    MCG_CAP_STATE, MCG_KEY(9, "Duty min 0.1%"), "controller output floor, %") \
  X(DUTY_MAX, "duty_max", MCG_RS, -MCG_DUTY_FULL, MCG_DUTY_FULL, MCG_DUTY_FULL, MCG_UNIT_PERMILLE, \
    MCG_CAP_STATE, MCG_KEY(10, "Duty max 0.1%"), "controller output ceiling, %") \
  X(SERVICE_MS, "service_ms", MCG_RW, 5, 250, 40, MCG_UNIT_MS, \
    MCG_CAP_NO, MCG_KEY(12, "Service ms"), "keypad and duty service period, ms") \
  X(LOG_INTERVAL, "log_interval", MCG_RW, 1, 255, 4, MCG_UNIT_MS, \
    MCG_CAP_NO, MCG_KEY(13, "Log interval ms"), "RAM log point spacing, ms") \
  X(LOG_COUNT, "log_count", MCG_RO, 0, MCG_LOG_POINTS, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "RAM log points recorded") \
  X(STREAM, "stream", MCG_RW, 0, 1, 0, MCG_UNIT_SWITCH, \
    MCG_CAP_NO, MCG_KEY(16, "Stream 0/1"), "stream blocks on") \
  X(CLUTCH, "clutch", MCG_RW, MCG_CLUTCH_ATTACHED, MCG_CLUTCH_ENGAGED, MCG_CLUTCH_ATTACHED, MCG_UNIT_CLUTCH, \
    MCG_CAP_ROW, MCG_KEY(14, "Clutch 1/2 eng"), \
    "clutch: 1 attached and disengaged, 2 engaged (as in mcg-csv(5))") \
  X(LOAD, "load", MCG_RW, 0, 1, 0, MCG_UNIT_SWITCH, \
    MCG_CAP_ROW, MCG_KEY(15, "Load relay 0/1"), "generator load relay closed") \
  X(RPM, "rpm", MCG_RO, 0, 7471, 0, MCG_UNIT_RPM, MCG_CAP_NO, MCG_NO_KEY, "measured speed over 16 ms, rpm") \
  X(COUNTS_16MS, "counts_16ms", MCG_RO, 0, 4080, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "encoder pulses in the last 16 ms") \
  X(SEQ_LEN, "seq_len", MCG_RO, 0, MCG_SEQ_MAX, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "command sequence entries stored") \
  X(SEQ_STATE, "seq_state", MCG_RW, MCG_SEQ_STOP, MCG_SEQ_LOOP, MCG_SEQ_STOP, MCG_UNIT_SEQ, \
    MCG_CAP_NO, MCG_NO_KEY, "sequence playback: stop, play, loop") \
  X(FLAGS, "flags", MCG_RO, 0, 31, 0, MCG_UNIT_FLAGS, \
    MCG_CAP_NO, MCG_NO_KEY, "saturated, logging, log_full, seq, seq_set") \
  X(RX_ERRORS, "rx_errors", MCG_RW, 0, 0, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "frames the board dropped; write 0 clears") \
  X(TX_DROPS, "tx_drops", MCG_RW, 0, 0, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "frames the board could not send; write 0 clears") \
  X(STREAM_SEQ, "stream_seq", MCG_RO, 0, 255, 0, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "sequence number of the next stream block") \
  X(COMMIT, "commit", MCG_RW, 0, 1, 0, MCG_UNIT_SWITCH, \
    MCG_CAP_NO, MCG_NO_KEY, \
    "write 1: the staged controller set becomes active at the next tick; 0: discards it; read: 1 if one is pending") \
  X(EXC_KIND, "exc_kind", MCG_RW, MCG_EXC_NONE, MCG_EXC_CHIRP, MCG_EXC_NONE, MCG_UNIT_EXC, \
    MCG_CAP_NO, MCG_NO_KEY, "excitation: none, prbs, staircase (a step is a staircase of one stair), chirp") \
  X(EXC_ORDER, "exc_order", MCG_RW, 2, 16, 9, MCG_UNIT_BITS, \
    MCG_CAP_NO, MCG_NO_KEY, "PRBS LFSR order n: 2^n - 1 bits per period") \
  X(EXC_STEPS, "exc_steps", MCG_RW, 1, 100, 1, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "staircase stairs above exc_offset") \
  X(EXC_DIV, "exc_div", MCG_RW, 1, 30000, 1, MCG_UNIT_MS, \
    MCG_CAP_NO, MCG_NO_KEY, "ticks per PRBS bit, stair or chirp level") \
  X(EXC_AMP, "exc_amp", MCG_RW, -2000, 2000, 0, MCG_UNIT_LEVEL, \
    MCG_CAP_NO, MCG_NO_KEY, "PRBS: offset +- amp; staircase: rise per stair; chirp: amplitude") \
  X(EXC_OFFSET, "exc_offset", MCG_RW, -1000, 1000, 0, MCG_UNIT_LEVEL, \
    MCG_CAP_NO, MCG_NO_KEY, "level the excitation starts from and ends at") \
  X(EXC_PERIODS, "exc_periods", MCG_RW, 0, 255, 1, MCG_UNIT_COUNT, \
    MCG_CAP_NO, MCG_NO_KEY, "periods played, 0: until exc_run 0") \
  X(EXC_RUN, "exc_run", MCG_RW, 0, 1, 0, MCG_UNIT_SWITCH, \
    MCG_CAP_NO, MCG_NO_KEY, \
    "write 1: start on the next stream sample (duty in mode open, rpm_cmd otherwise); 0: stop; read: 1 running") \
  X(EXC_F0, "exc_f0", MCG_RW, 1, 30000, 10, MCG_UNIT_CHZ, \
    MCG_CAP_NO, MCG_NO_KEY, "chirp: start frequency, Hz") \
  X(EXC_F1, "exc_f1", MCG_RW, 1, 30000, 1000, MCG_UNIT_CHZ, \
    MCG_CAP_NO, MCG_NO_KEY, "chirp: end frequency, Hz") \
  X(EXC_SWEEP, "exc_sweep", MCG_RW, 1, 600, 10, MCG_UNIT_S, \
    MCG_CAP_NO, MCG_NO_KEY, "chirp: seconds per sweep (one period)") /* clang-format on */

#define MCG_MODE_OPEN 0u /* duty from MCG_REG_DUTY (keypad up/down) */
#define MCG_MODE_P 1u    /* u = bias + Kp e */
#define MCG_MODE_PI 2u   /* incremental, b0 b1 */
#define MCG_MODE_PID 3u  /* incremental, b0 b1 b2 */
#define MCG_MODE_COUNT 4u

/* Clutch states, numbered as the clutch column of mcg-csv(5) in every tool. State 0 (motor alone, the
 * clutch removed) exists on the bench but not for the board, whose clutch is mounted. */
#define MCG_CLUTCH_ATTACHED 1u /* attached and disengaged */
#define MCG_CLUTCH_ENGAGED 2u

/* Excitations (excite.c): the generators the board plays. */
#define MCG_EXC_NONE 0u
#define MCG_EXC_PRBS 1u      /* maximal-length LFSR, exc_order bits, exc_div ticks per bit */
#define MCG_EXC_STAIRCASE 2u /* exc_steps + 1 levels, exc_div ticks each */
#define MCG_EXC_CHIRP 3u     /* linear sweep exc_f0 -> exc_f1 over exc_sweep s, a level every exc_div ticks */

#define MCG_SEQ_STOP 0u
#define MCG_SEQ_PLAY 1u /* play once from entry 0 */
#define MCG_SEQ_LOOP 2u /* play, restart at the end */

#define MCG_FLAG_SATURATED 0x01u /* the controller output is at duty_min or duty_max */
#define MCG_FLAG_LOGGING 0x02u   /* RAM log recording */
#define MCG_FLAG_LOG_FULL 0x04u  /* RAM log holds MCG_LOG_POINTS points */
#define MCG_FLAG_SEQ 0x08u       /* sequence playing */
#define MCG_FLAG_SEQ_SET 0x10u   /* the playing sequence owns the controller's set (stages into it) */

/* ---- RAM log ---------------------------------------------------------------------------------- */
#define MCG_LOG_XADDR 0x9500u  /* external RAM address of the log */
#define MCG_LOG_POINTS 255u    /* points; each is i16 LE: encoder counts during its interval, signed with the drive */
#define MCG_LOG_DUMP_CHUNK 16u /* points per MCG_MSG_LOG_DATA frame */
#define MCG_LOG_DUMP_FRAMES 16u
/* MCG_MSG_LOG_DATA payload: index u8 of the first point, n u8, then n x u16 points */
#define MCG_LOGDATA_HEADER sizeof(McgLogDataHeader)

/* ---- Stream blocks (protocol 2) --------------------------------------------------------------- */
/* Payload: seq u8, rpm_cmd i16 (at the block's last sample), then MCG_STREAM_SAMPLES samples of
 * MCG_STREAM_SAMPLE_BYTES bytes. Sample k describes one MCG_STREAM_PERIOD_MS interval of 1 ms ticks,
 * the samples of a block back to back; its 24 bits, little-endian:
 *   bits  0..10  duty, i11, 1/1000: the mean of the PWM duty over the interval's ticks, rounded half
 *                away from zero (what drove the motor: v = duty / 1000 * supply)
 *   bits 11..20  counts, i10: encoder pulses during the interval, signed with the direction of the
 *                last non-zero drive (the counter input has no direction); +-MCG_STREAM_COUNTS_MAX
 *                means saturated
 *   bit  21      clutch engaged, bit 22 load relay closed (both as at the interval's last tick)
 *   bit  23      rpm_cmd written during the interval (the value in force from then on is the
 *                header's if no later sample of the block has this bit)
 * Budget at 9600 8N1 (960 B/s): 3 + 16 x 3 = 51 payload + 5 frame bytes per 64 ms = 875 B/s, 91 %. */
#define MCG_STREAM_PERIOD_MS 4u
#define MCG_STREAM_SAMPLES 16u
#define MCG_STREAM_HEADER sizeof(McgStreamHeader)
#define MCG_STREAM_SAMPLE_BYTES 3u
#define MCG_STREAM_PAYLOAD (MCG_STREAM_HEADER + MCG_STREAM_SAMPLES * MCG_STREAM_SAMPLE_BYTES)
#define MCG_STREAM_COUNTS_MAX 511
#define MCG_STREAM_BIT_CLUTCH 0x20u /* in the sample's third byte */
#define MCG_STREAM_BIT_LOAD 0x40u
#define MCG_STREAM_BIT_CMD 0x80u

/* ---- Command sequence (played back from RAM) -------------------------------------------------- */
/* Entry (5 bytes): delay_ms u16 after the previous entry, reg u8, value i16. Played as a register
 * write through the same checks as MCG_CMD_WRITE. MCG_CMD_SEQ_WRITE carries up to 12 entries. */
#define MCG_SEQ_MAX 128u
#define MCG_SEQ_ENTRY_BYTES sizeof(McgSeqEntry)
#define MCG_SEQ_WRITE_MAX 12u
#define MCG_SEQ_XADDR 0x9700u /* external RAM address of the sequence table */

/* ---- Keypad (EMAC 4x4) key codes -------------------------------------------------------------- */
#define MCG_KEY_NONE 0xFFu /* 0..9 digits, 0x0A..0x0F the letter keys A..F */

/* CRC-16/CCITT-FALSE, one byte: crc = mcg_crc16_update(crc, byte), starting at MCG_CRC_INIT.
 * Table-free form (x = (crc >> 8) ^ byte; x ^= x >> 4; crc = crc << 8 ^ x << 12 ^ x << 5 ^ x). */
static inline unsigned mcg_crc16_update(unsigned crc, unsigned byte) {
  unsigned x = ((crc >> 8) ^ byte) & 0xFFu;
  x ^= x >> 4;
  return ((crc << 8) ^ (x << 12) ^ (x << 5) ^ x) & 0xFFFFu;
}

#endif
