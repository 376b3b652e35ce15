"""The 802.11 DCF link-layer assumptions (frame size, retries, rate model, coding) that turn a
packet error rate into rate, delay and residual loss: one record, read by the retry chain
(`frames`) and the link budget (`budget`), so that neither imports the other for it."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field


class LinkLayer(BaseModel):
    """802.11 DCF link-layer assumptions turning PER into rate, delay and residual loss."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    packet_bytes: int = Field(1500, gt=0)
    mac_overhead_bytes: int = Field(36, ge=0)
    retry_limit: int = Field(6, ge=0)  # retransmissions; dot11ShortRetryLimit 7 = 7 attempts
    rate_model: Literal["dcf", "phy"] = "dcf"
    processing_delay_ms: float = Field(0.1, ge=0)
    coding: Literal["bcc", "uncoded"] = "bcc"
    implementation_loss_db: float = Field(5.0, ge=0)
    fallback_after: int | None = Field(4, ge=1)  # attempts at the chosen level before the base rate

    @property
    def mpdu_bits(self) -> int:
        return 8 * (self.packet_bytes + self.mac_overhead_bytes)


DEFAULT_LINK_LAYER = LinkLayer()
