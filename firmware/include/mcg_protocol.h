/* mcg_protocol.h: the wire contract between the SAB 80C515 board and the host (see mcg-protocol(7)).
 *
 * One header for both sides: the firmware (SDCC, C99) and the host tools (C++20) include it, so every
 * constant below is defined exactly once. It holds only macros, one enum-free set of ids and a
 * conversion-clean inline CRC, so it compiles warning-free as C99 and as C++ (-Wold-style-cast,
 * -Wconversion).
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
#define MCG_PROTOCOL_VERSION 1u

/* Firmware version reported by MCG_CMD_VERSION. */
#define MCG_FW_VERSION_MAJOR 0u
#define MCG_FW_VERSION_MINOR 1u
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
#define MCG_ST_BUSY 10u      /* not now: log recording, or sequence playing */
#define MCG_ST_COUNT 11u

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

/* ---- Registers: id, type, unit, range, default (all travel as i16 little-endian) -------------- */
#define MCG_REG_MODE 0x01u         /* rw  enum  MCG_MODE_*                        default 0 */
#define MCG_REG_RPM_CMD 0x02u      /* rw  rpm   120..720 (420 +- 300)             default 420 */
#define MCG_REG_DUTY 0x03u         /* rw  1/1000 duty_min..duty_max; read = output; write only in open loop */
#define MCG_REG_DUTY_STEP 0x04u    /* rw  1/1000 1..1000 keypad up/down step     default 10 */
#define MCG_REG_DUTY_BIAS 0x05u    /* rw  1/1000 -1000..1000 P mode: u = bias + Kp e   default 0 */
#define MCG_REG_KP 0x06u           /* rw  Q(F)  1/1000 per count/ms, P mode gain  default 0 */
#define MCG_REG_B0 0x07u           /* rw  Q(F)  PI/PID: u[n] = u[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2] */
#define MCG_REG_B1 0x08u           /* rw  Q(F) */
#define MCG_REG_B2 0x09u           /* rw  Q(F)  (ignored in PI mode) */
#define MCG_REG_COEF_FRAC 0x0Au    /* rw  bits  F = 0..12, fractional bits of KP, B0..B2   default 8 */
#define MCG_REG_DUTY_MIN 0x0Bu     /* rw  1/1000 -1000..duty_max, saturation       default 0 */
#define MCG_REG_DUTY_MAX 0x0Cu     /* rw  1/1000 duty_min..1000, saturation        default 1000 */
#define MCG_REG_SERVICE_MS 0x0Du   /* rw  ms    5..250 keypad/duty service period default 40 */
#define MCG_REG_LOG_INTERVAL 0x0Eu /* rw  ms    1..255 RAM log point spacing      default 4 */
#define MCG_REG_LOG_COUNT 0x0Fu    /* ro  points recorded so far, 0..255 */
#define MCG_REG_STREAM 0x10u       /* rw  0/1   stream blocks on                  default 0 */
#define MCG_REG_CLUTCH 0x11u       /* rw  0/1   clutch engaged                    default 0 */
#define MCG_REG_LOAD 0x12u         /* rw  0/1   generator load relay closed       default 0 */
#define MCG_REG_RPM 0x13u          /* ro  rpm   measured over MCG_SPEED_WINDOW_MS */
#define MCG_REG_COUNTS_16MS 0x14u  /* ro  counts in the last 16 ms (rpm = c * 1875 / 1024) */
#define MCG_REG_SEQ_LEN 0x15u      /* ro  entries stored, 0..MCG_SEQ_MAX */
#define MCG_REG_SEQ_STATE 0x16u    /* rw  MCG_SEQ_*                               default 0 */
#define MCG_REG_FLAGS 0x17u        /* ro  MCG_FLAG_* bits */
#define MCG_REG_RX_ERRORS 0x18u    /* rw  frames dropped (CRC, length, timeout, overrun); write 0 clears */
#define MCG_REG_TX_DROPS 0x19u     /* rw  frames not sent for lack of transmit room; write 0 clears */
#define MCG_REG_STREAM_SEQ 0x1Au   /* ro  sequence number of the next stream block */
#define MCG_REG_COUNT 0x1Bu        /* ids 0x01..MCG_REG_COUNT-1 exist */

#define MCG_MODE_OPEN 0u /* duty from MCG_REG_DUTY (keypad up/down) */
#define MCG_MODE_P 1u    /* u = bias + Kp e */
#define MCG_MODE_PI 2u   /* incremental, b0 b1 */
#define MCG_MODE_PID 3u  /* incremental, b0 b1 b2 */
#define MCG_MODE_COUNT 4u

#define MCG_SEQ_STOP 0u
#define MCG_SEQ_PLAY 1u /* play once from entry 0 */
#define MCG_SEQ_LOOP 2u /* play, restart at the end */

#define MCG_FLAG_SATURATED 0x01u /* the controller output is at duty_min or duty_max */
#define MCG_FLAG_LOGGING 0x02u   /* RAM log recording */
#define MCG_FLAG_LOG_FULL 0x04u  /* RAM log holds MCG_LOG_POINTS points */
#define MCG_FLAG_SEQ 0x08u       /* sequence playing */

/* ---- RAM log ---------------------------------------------------------------------------------- */
#define MCG_LOG_XADDR 0x9500u  /* external RAM address of the log */
#define MCG_LOG_POINTS 255u    /* points; each is u16 LE: encoder counts during its interval */
#define MCG_LOG_DUMP_CHUNK 16u /* points per MCG_MSG_LOG_DATA frame */
#define MCG_LOG_DUMP_FRAMES 16u
/* MCG_MSG_LOG_DATA payload: index u8 of the first point, n u8, then n x u16 points */
#define MCG_LOGDATA_HEADER 2u

/* ---- Stream blocks ---------------------------------------------------------------------------- */
/* Payload: seq u8, duty i16 (1/1000, at the last sample), rpm_cmd i16, then MCG_STREAM_SAMPLES x u8:
 * encoder counts during each 2 ms sample period (saturated at 255). 16 samples = 32 ms per block:
 * 5 + 5 + 16 = 26 bytes per 32 ms = 812.5 B/s of the 960 B/s at 9600 8N1. */
#define MCG_STREAM_PERIOD_MS 2u
#define MCG_STREAM_SAMPLES 16u
#define MCG_STREAM_HEADER 5u

/* ---- Command sequence (played back from RAM) -------------------------------------------------- */
/* Entry (5 bytes): delay_ms u16 after the previous entry, reg u8, value i16. Played as a register
 * write through the same checks as MCG_CMD_WRITE. MCG_CMD_SEQ_WRITE carries up to 12 entries. */
#define MCG_SEQ_MAX 128u
#define MCG_SEQ_ENTRY_BYTES 5u
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
